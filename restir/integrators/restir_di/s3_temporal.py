"""Stage 3, temporal reuse: the pixel's new reservoir with last frame's final reservoir where
this pixel's primary hit was seen (generalized balance / Talbot MIS over the two; ALGORITHMS.md 4.2).

The current primary hit is projected into the previous camera; the previous pixel is the
temporal technique if it is on screen, had a primary hit and is geometrically similar (a
decision on G-buffers only). The previous confidence is capped to temporal_cap x the current
one before any weight is computed (the one cap, restir/resampling/ris.py). Light samples move
unchanged (J = 1). Static scenes: the previous domain is evaluated with the current geometry.
Reads: scene, G-buffer, previous G-buffer and camera, reservoirs (initial), previous final
reservoirs. Writes: reservoirs_out, nonfinite.
"""
import warp as wp

from ...device.camera import Camera, project_to_pixel
from ...device.rng import rng_key, rng_uniform
from ...device.scene_device import SceneDevice
from ...device.types import STAGE_DI_TEMPORAL
from ...resampling.mis import balance_weight, techniques_vec
from ...resampling.ris import cap_confidence, ris_contribution_weight, ris_init, ris_stream
from .gbuffer import load_shading, similar_surfaces
from .params import DIParams
from .reservoir import DIReservoir, luminance, unshadowed_contribution


@wp.kernel
def temporal_kernel(offset: int, scene: SceneDevice, params: DIParams, prev_camera: Camera,
                    gb_tri: wp.array(dtype=wp.int32), gb_bary: wp.array(dtype=wp.vec2), gb_t: wp.array(dtype=float),
                    gb_dir: wp.array(dtype=wp.vec3), prev_tri: wp.array(dtype=wp.int32),
                    prev_bary: wp.array(dtype=wp.vec2), prev_t: wp.array(dtype=float), prev_dir: wp.array(dtype=wp.vec3),
                    reservoirs: wp.array(dtype=DIReservoir), prev_reservoirs: wp.array(dtype=DIReservoir),
                    reservoirs_out: wp.array(dtype=DIReservoir), nonfinite: wp.array(dtype=wp.int32)):
    pixel = wp.tid() + offset
    c = reservoirs[pixel]
    reservoirs_out[pixel] = c
    nonfinite[pixel] = 0
    sc = load_shading(scene, gb_tri, gb_bary, gb_t, gb_dir, pixel)
    if sc.valid == 0:
        return
    # ---- the temporal technique: where this hit was seen last frame (geometry only)
    xy = project_to_pixel(prev_camera, sc.hit.p)
    qx = int(wp.floor(xy[0]))
    qy = int(wp.floor(xy[1]))
    if xy[0] < 0.0 or xy[1] < 0.0 or qx >= prev_camera.width or qy >= prev_camera.height:
        return
    q = qy * prev_camera.width + qx
    sq = load_shading(scene, prev_tri, prev_bary, prev_t, prev_dir, q)
    if sq.valid == 0 or not similar_surfaces(sc, sq):
        return
    p_c = luminance(unshadowed_contribution(scene, sc, c))
    if params.mut_skip_zero_canonical != 0 and p_c * c.W == 0.0:
        return
    r = prev_reservoirs[q]
    Mq = cap_confidence(r.M, params.temporal_cap * c.M)
    key = rng_key(params.seed, params.frame, wp.uint32(STAGE_DI_TEMPORAL), wp.uint32(pixel))
    base = wp.uint32(params.sample * 4)
    d = techniques_vec()
    s = ris_init()
    # current sample
    d[0] = p_c * c.M
    d[1] = luminance(unshadowed_contribution(scene, sq, c)) * Mq
    s = ris_stream(s, balance_weight(d, 2, 0) * p_c * c.W, p_c, c.M, 0, rng_uniform(key, base))
    # previous sample
    p_c_at_q = luminance(unshadowed_contribution(scene, sc, r))
    d[0] = p_c_at_q * c.M
    d[1] = luminance(unshadowed_contribution(scene, sq, r)) * Mq
    w_prev = balance_weight(d, 2, 1) * p_c_at_q * r.W
    if params.mut_temporal_overweight != 0:
        w_prev = w_prev * 1.5
    s = ris_stream(s, w_prev, p_c_at_q, Mq, 1, rng_uniform(key, base + wp.uint32(1)))
    out = c
    if s.selected == 1:
        out = r
    out.W = ris_contribution_weight(s, 1.0)
    out.M = s.M
    if s.selected < 0:
        out.light_tri = -2
    reservoirs_out[pixel] = out
    nonfinite[pixel] = s.nonfinite
