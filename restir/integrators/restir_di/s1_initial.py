"""Stage 1, initial resampling: RIS over N_L light and N_B BSDF candidates per pixel
(Bitterli 2020, Alg. 3; the two generators combined as in Talbot 2005's multiple-distribution RIS).

Light candidates come from the NEE light sampler (power-proportional triangles uniform by area,
delta lights, or the environment); BSDF candidates trace the smooth lobes' sample and keep the emitter it hits
(or the environment it escapes to). Every candidate y is a light point in its own measure and
is weighted by the balance heuristic over both generators:

    w(y) = p_hat(y) / (N_L p_L(y) + N_B p_B(y)),   W = w_sum / p_hat(y_selected),   M = 1,

with p_hat = luminance(f_s Le G) (unshadowed: visibility is the next stage's job). A BSDF
sample that picks a delta lobe, misses every emitter or fails is a candidate of weight 0.
Delta-only surfaces and misses keep an empty reservoir.
By default this stage, the visibility stage and temporal reuse run as one kernel (s3_temporal.py);
`stages.split` launches each as a kernel of its own, timed apart.
Reads: scene, G-buffer (gb). Writes: reservoirs, events (non-finite and zero weights, rays).
"""
import warp as wp

from ...device.bsdf import bsdf_is_delta_only, bsdf_sample
from ...device.color import luminance
from ...device.intersect import T_MAX, offset_origin, trace_closest
from ...device.lights import sample_light
from ...device.rng import rng_key, rng_uniform, rng_uniform2
from ...device.sampling import to_world
from ...device.scene_device import SceneDevice
from ...device.streams import (DI_DIM_CANDIDATE_POINT, DI_DIM_CANDIDATE_RIS, DI_DIM_CANDIDATE_SELECT,
                               DI_DIMS_PER_CANDIDATE, DIMS_PER_SAMPLE, STAGE_DI_INITIAL)
from ...device.types import ENV_NONE, LIGHT_ENV
from ...resampling.ris import ris_finalize, ris_init, ris_stream
from ..common.events import EventCounts, packed_events, stage_events
from ..common.gbuffer import GBuffer
from ..common.shading import Shading, load_shading_outlined
from .kernel_module import SPLIT_MODULE
from .params import DIParams
from .reservoir import (DIReservoir, candidate_densities, empty_reservoir, on_triangle, store,
                        unshadowed_contribution)


@wp.func
def light_candidate(scene: SceneDevice, sh: Shading, u_sel: float, u: wp.vec2) -> DIReservoir:
    cand = empty_reservoir()
    ls = sample_light(scene, sh.hit.p, u_sel, u)
    if ls.pdf > 0.0:
        if ls.is_env != 0:
            cand.light_tri = LIGHT_ENV
            cand.light_y = ls.wi
        elif ls.is_delta != 0:
            cand.light_tri = ls.tri  # the delta light's identity: nothing else to keep
        else:
            cand = on_triangle(ls.tri, ls.bary)
    return cand


@wp.func
def bsdf_direction(sh: Shading, u_lobe: float, u: wp.vec2) -> wp.vec4:
    """(world direction, 1) of a BSDF sample of the smooth lobes; (0, 0, 0, 0) for a delta lobe or
    a failed sample (the candidate then has weight 0)."""
    bs = bsdf_sample(sh.mat, sh.wi, u_lobe, u)
    if bs.valid == 0 or bs.is_delta != 0 or bs.pdf <= 0.0:
        return wp.vec4(0.0)
    d = wp.normalize(to_world(sh.frame, bs.wo))
    return wp.vec4(d[0], d[1], d[2], 1.0)


@wp.func
def light_point_along(scene: SceneDevice, sh: Shading, d: wp.vec3) -> DIReservoir:
    """The light point the ray from sh along d reaches first (no sample: light_tri = LIGHT_NONE)."""
    cand = empty_reservoir()
    h = trace_closest(scene, offset_origin(sh.hit.p, sh.hit.ng, d), d, T_MAX)
    if h.valid != 0:
        if scene.tri_light_pdf[h.tri] > 0.0:
            cand = on_triangle(h.tri, h.bary)
    elif scene.env_kind != ENV_NONE:
        cand.light_tri = LIGHT_ENV
        cand.light_y = d
    return cand


@wp.func
def initial_reservoir(scene: SceneDevice, params: DIParams, sh: Shading, pixel: int):
    """The stage's work for one pixel, (reservoir, events): what the split kernel stores and the
    fused kernel (s3_temporal.py) keeps in registers."""
    out = empty_reservoir()
    s = ris_init()
    rays = int(0)
    if sh.valid != 0 and bsdf_is_delta_only(sh.mat) == 0:
        key = rng_key(params.seed, params.frame, wp.uint32(STAGE_DI_INITIAL), wp.uint32(pixel))
        base = wp.uint32(params.sample) * wp.uint32(DIMS_PER_SAMPLE)
        n_L = float(params.candidates)
        n_B = float(params.bsdf_candidates)
        for j in range(params.candidates + params.bsdf_candidates):
            dim = base + wp.uint32(j * DI_DIMS_PER_CANDIDATE)
            u_sel = rng_uniform(key, dim + wp.uint32(DI_DIM_CANDIDATE_SELECT))
            u = rng_uniform2(key, dim + wp.uint32(DI_DIM_CANDIDATE_POINT))
            cand = empty_reservoir()
            if j < params.candidates:
                cand = light_candidate(scene, sh, u_sel, u)
            else:
                bd = bsdf_direction(sh, u_sel, u)
                if bd[3] > 0.0:
                    cand = light_point_along(scene, sh, wp.vec3(bd[0], bd[1], bd[2]))
                    rays += 1
            # Zero-weight candidates are still inputs (they count and are never selected).
            p = candidate_densities(scene, sh, cand, params.bsdf_candidates)
            p_source = n_L * p[0] + n_B * p[1]
            w = float(0.0)
            p_hat = float(0.0)
            if p_source > 0.0:
                p_hat = luminance(unshadowed_contribution(scene, sh, cand))
                w = p_hat / p_source
            s = ris_stream(s, w, p_hat, 0.0, j, rng_uniform(key, dim + wp.uint32(DI_DIM_CANDIDATE_RIS)))
            if s.selected == j:
                out = cand
        f = ris_finalize(s, 1.0)
        f.M = 1.0  # the pixel's initial RIS is one technique of confidence 1, whatever its candidate count
        out = store(out, f)
    return out, stage_events(s, 0, rays)


@wp.kernel(module=SPLIT_MODULE)
def initial_kernel(offset: int, scene: SceneDevice, params: DIParams, gb: GBuffer,
                   reservoirs: wp.array(dtype=DIReservoir), events: wp.array(dtype=EventCounts)):
    """The stage on its own (`stages.split`)."""
    pixel = wp.tid() + offset
    r, ev = initial_reservoir(scene, params, load_shading_outlined(scene, gb, pixel), pixel)
    reservoirs[pixel] = r
    events[pixel] = packed_events(ev)
