"""Stage 3, temporal reuse: the pixel's new reservoir with last frame's final reservoir where
this pixel's primary hit was seen (generalized balance / Talbot MIS over the two; ALGORITHMS.md 4.2).

The current primary hit is projected into the previous camera; the previous pixel is the
temporal technique if it is on screen, had a primary hit and is geometrically similar (a
decision on G-buffers only). The previous confidence is capped to temporal_cap x the current
one before any weight is computed (the one cap, restir/resampling/ris.py). Light samples move
unchanged (J = 1). Static scenes: the previous domain is evaluated with the current geometry.
With visibility-aware targets, each cross-domain target costs one shadow ray (two per pixel).
Reads: scene, G-buffer, previous G-buffer and camera, reservoirs (initial), previous final
reservoirs. Writes: reservoirs_out, events.
"""
import warp as wp

from ...device.camera import Camera, project_to_pixel
from ...device.rng import rng_key, rng_uniform
from ...device.scene_device import SceneDevice
from ...device.types import STAGE_DI_TEMPORAL
from ...resampling.mis import balance_weight, techniques_vec
from ...resampling.ris import cap_confidence, ris_contribution_weight, ris_init, ris_stream
from .events import stage_events
from .gbuffer import load_shading, similar_surfaces
from .params import DIParams
from .reservoir import DIReservoir, own_target, target


@wp.kernel
def temporal_kernel(offset: int, scene: SceneDevice, params: DIParams, prev_camera: Camera,
                    gb_tri: wp.array(dtype=wp.int32), gb_bary: wp.array(dtype=wp.vec2), gb_t: wp.array(dtype=float),
                    gb_dir: wp.array(dtype=wp.vec3), prev_tri: wp.array(dtype=wp.int32),
                    prev_bary: wp.array(dtype=wp.vec2), prev_t: wp.array(dtype=float), prev_dir: wp.array(dtype=wp.vec3),
                    reservoirs: wp.array(dtype=DIReservoir), prev_reservoirs: wp.array(dtype=DIReservoir),
                    reservoirs_out: wp.array(dtype=DIReservoir), events: wp.array(dtype=wp.vec4i)):
    pixel = wp.tid() + offset
    c = reservoirs[pixel]
    reservoirs_out[pixel] = c
    events[pixel] = wp.vec4i(0)
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
    vis = params.visibility
    p_c = own_target(scene, sc, c, vis)
    if params.mut_skip_zero_canonical != 0 and p_c * c.W == 0.0:
        return
    r = prev_reservoirs[q]
    Mq = cap_confidence(r.M, params.temporal_cap * c.M)
    key = rng_key(params.seed, params.frame, wp.uint32(STAGE_DI_TEMPORAL), wp.uint32(pixel))
    base = wp.uint32(params.sample * 4)
    d = techniques_vec()
    s = ris_init()
    # current sample
    t_q = target(scene, sq, c, vis)
    d[0] = p_c * c.M
    d[1] = t_q[0] * Mq
    s = ris_stream(s, balance_weight(d, 2, 0) * p_c * c.W, p_c, c.M, 0, rng_uniform(key, base))
    # previous sample
    t_c = target(scene, sc, r, vis)
    p_c_at_q = t_c[0]
    d[0] = p_c_at_q * c.M
    d[1] = own_target(scene, sq, r, vis) * Mq
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
    failed = wp.where(r.W > 0.0 and p_c_at_q <= 0.0, 1, 0)
    events[pixel] = stage_events(s, failed, int(t_q[1] + t_c[1]))
