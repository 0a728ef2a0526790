"""Stage 5, shading: the pixel's estimate of direct illumination (max_depth 2).

L = emission + f_s Le G V(y) W  (the resampled smooth part; V traced here, unless targets were
      visibility-aware: then W > 0 already implies V = 1 at this pixel)
      + the delta lobes' direct light, by BSDF sampling (kept only when a delta lobe is chosen;
        the smooth lobes are the resampled part's), all times the filter weight.
Reads: scene, G-buffer, filter weight, emission (all from the primary-hit stage), reservoirs. Writes: sample_L, events (NaN/inf outputs, counted
and kept: never silently zeroed; rays).
"""
import warp as wp

from ...device.bsdf import bsdf_sample
from ...device.intersect import T_MAX, offset_origin, trace_closest
from ...device.lights import env_eval, triangle_emission
from ...device.rng import rng_key, rng_uniform, rng_uniform2
from ...device.sampling import to_world
from ...device.scene_device import SceneDevice
from ...device.streams import DI_DIM_SHADE_DIR, DI_DIM_SHADE_LOBE, DIMS_PER_SAMPLE, STAGE_DI_SHADE
from ...device.types import ENV_NONE
from ..common.events import EventCounts, output_events, packed_events
from ..common.gbuffer import GBuffer
from ..common.shading import load_shading
from .params import DIParams
from .reservoir import DIReservoir, light_visible, unshadowed_contribution


@wp.kernel
def shade_kernel(offset: int, scene: SceneDevice, params: DIParams, gb: GBuffer,
                 primary_weight: wp.array(dtype=float), emission: wp.array(dtype=wp.vec3),
                 reservoirs: wp.array(dtype=DIReservoir), sample_L: wp.array(dtype=wp.vec3),
                 events: wp.array(dtype=EventCounts)):
    pixel = wp.tid() + offset
    L = emission[pixel]
    rays = int(0)
    sh = load_shading(scene, gb, pixel)
    if sh.valid != 0:
        hit = sh.hit
        weight = primary_weight[pixel]
        # ---- resampled smooth part
        r = reservoirs[pixel]
        if r.W > 0.0:
            f = unshadowed_contribution(scene, sh, r)
            if params.visibility != 0:
                L += f * (r.W * weight)
            elif f[0] > 0.0 or f[1] > 0.0 or f[2] > 0.0:
                rays += 1
                if light_visible(scene, hit, r):
                    L += f * (r.W * weight)
        # ---- delta lobes: one BSDF sample, kept when it chose a delta lobe
        key = rng_key(params.seed, params.frame, wp.uint32(STAGE_DI_SHADE), wp.uint32(pixel))
        base = wp.uint32(params.sample) * wp.uint32(DIMS_PER_SAMPLE)
        bs = bsdf_sample(sh.mat, sh.wi, rng_uniform(key, base + wp.uint32(DI_DIM_SHADE_LOBE)),
                         rng_uniform2(key, base + wp.uint32(DI_DIM_SHADE_DIR)))
        if bs.valid != 0 and bs.is_delta != 0:
            d = wp.normalize(to_world(sh.frame, bs.wo))
            h2 = trace_closest(scene, offset_origin(hit.p, hit.ng, d), d, T_MAX)
            rays += 1
            Le = wp.vec3(0.0)
            if h2.valid != 0:
                Le = triangle_emission(scene, h2.tri, h2.ns, -d)
            elif scene.env_kind != ENV_NONE:
                Le = env_eval(scene, d)
            L += wp.cw_mul(bs.weight, Le) * weight
    sample_L[pixel] = L
    events[pixel] = packed_events(output_events(L, rays))
