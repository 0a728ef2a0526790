"""Stage 2, initial resampling: RIS over `candidates` light samples per pixel (Bitterli 2020, Alg. 3).

Candidates y_j come from the NEE light sampler (power-proportional triangles uniform by area,
or the environment), with density p(y_j) in the sample's measure; the target is
p_hat(y) = luminance(f_s Le G) without visibility. Weights w_j = p_hat(y_j) / (N p(y_j)),
W = w_sum / p_hat(y), M = 1. Delta-only surfaces and misses keep an empty reservoir.
Reads: scene, G-buffer. Writes: reservoirs, nonfinite (count of NaN/inf weights, per pixel).
"""
import warp as wp

from ...device.bsdf import bsdf_is_delta_only
from ...device.lights import sample_light
from ...device.rng import rng_key, rng_uniform, rng_uniform2
from ...device.scene_device import SceneDevice
from ...device.types import DIMS_PER_SAMPLE, STAGE_DI_INITIAL
from ...resampling.ris import ris_contribution_weight, ris_init, ris_stream
from .gbuffer import load_shading
from .params import DIParams
from .reservoir import DIReservoir, empty_reservoir, luminance, unshadowed_contribution


@wp.kernel
def initial_kernel(offset: int, scene: SceneDevice, params: DIParams, gb_tri: wp.array(dtype=wp.int32),
                   gb_bary: wp.array(dtype=wp.vec2), gb_t: wp.array(dtype=float), gb_dir: wp.array(dtype=wp.vec3),
                   reservoirs: wp.array(dtype=DIReservoir), nonfinite: wp.array(dtype=wp.int32)):
    pixel = wp.tid() + offset
    out = empty_reservoir()
    bad = int(0)
    sh = load_shading(scene, gb_tri, gb_bary, gb_t, gb_dir, pixel)
    if sh.valid != 0:
        if bsdf_is_delta_only(sh.mat) == 0:
            key = rng_key(params.seed, params.frame, wp.uint32(STAGE_DI_INITIAL), wp.uint32(pixel))
            base = wp.uint32(params.sample) * wp.uint32(DIMS_PER_SAMPLE)
            s = ris_init()
            for j in range(params.candidates):
                dim = base + wp.uint32(4 * j)
                ls = sample_light(scene, sh.hit.p, rng_uniform(key, dim), rng_uniform2(key, dim + wp.uint32(1)))
                cand = empty_reservoir()
                p_source = float(0.0)
                if ls.pdf > 0.0:
                    cand.light_tri = ls.tri
                    if ls.is_env != 0:
                        cand.light_y = ls.wi
                        p_source = ls.pdf
                    else:
                        cand.light_y = ls.p
                        cand.light_n = ls.n
                        cand.light_ns = ls.ns
                        # the sampler's solid-angle pdf, converted to area measure at the light
                        p_source = ls.pdf * wp.abs(wp.dot(ls.n, ls.wi)) / (ls.dist * ls.dist)
                # Zero-weight candidates are still inputs (they count and are never selected).
                w = float(0.0)
                p_hat = float(0.0)
                if p_source > 0.0:
                    p_hat = luminance(unshadowed_contribution(scene, sh, cand))
                    w = p_hat / (float(params.candidates) * p_source)
                s = ris_stream(s, w, p_hat, 0.0, j, rng_uniform(key, dim + wp.uint32(3)))
                if s.selected == j:
                    out = cand
            bad = s.nonfinite
            out.W = ris_contribution_weight(s, 1.0)
            out.M = 1.0
            if out.W <= 0.0:
                out = empty_reservoir()
                out.M = 1.0
    reservoirs[pixel] = out
    nonfinite[pixel] = bad
