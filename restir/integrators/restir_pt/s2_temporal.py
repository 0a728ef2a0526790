"""Stage 2, temporal reuse: the pixel's new reservoir with last frame's final reservoir where
this pixel's primary hit was seen, by generalized balance (Talbot) MIS over the two techniques
(ALGORITHMS.md 4.2). The previous confidence is capped to temporal_cap x the current one before
any weight is computed (cap_history). Both samples are shifted: the current one into the
previous domain (its density there, for its own weight) and the history's into this one.
The previous domain is the previous primary hit seen by the previous camera, evaluated with the
current scene (static scenes). The replay is done inline in this pass (no separate retrace
pass): the same function runs for both directions with the same seeds, so the two passes of
the official code cannot disagree here by construction.
Reads: scene, G-buffer, previous G-buffer and camera, previous final reservoirs, reservoirs.
Writes: reservoirs_out, events.
"""
import warp as wp

from ...device.camera import Camera
from ...device.color import luminance
from ...device.rng import rng_key, rng_uniform
from ...device.scene_device import SceneDevice
from ...device.streams import PT_TEMPORAL_DIMS_PER_SAMPLE, STAGE_PT_TEMPORAL
from ...resampling.mis import talbot_weight2
from ...resampling.ris import cap_history, ris_finalize, ris_init, ris_merge
from ..common.events import stage_events
from ..common.gbuffer import GBuffer
from ..common.reuse_domains import NO_PIXEL, temporal_neighbor
from ..common.shading import load_shading
from .params import PTRParams
from .path_sample import ORIGIN_TEMPORAL, PathReservoir, holds_path, store, with_origin
from .shift import ShiftResult, shift_counts, shift_path

CURRENT = wp.constant(0)
HISTORY = wp.constant(1)


def make_temporal_kernel(shift=shift_path, drop_failed: bool = False, module=None):
    """The temporal kernel over a shift function; drop_failed builds the mutation that drops a
    history whose shift failed (its M and its density in the current sample's weight)."""

    @wp.kernel(module=module)
    def temporal_kernel(offset: int, scene: SceneDevice, params: PTRParams, prev_camera: Camera, gb: GBuffer,
                        prev_gb: GBuffer, prev_reservoirs: wp.array(dtype=PathReservoir),
                        reservoirs: wp.array(dtype=PathReservoir), reservoirs_out: wp.array(dtype=PathReservoir),
                        shifts: wp.array(dtype=wp.vec4i), events: wp.array(dtype=wp.vec4i)):
        pixel = wp.tid() + offset
        c = reservoirs[pixel]
        reservoirs_out[pixel] = c
        events[pixel] = wp.vec4i(0)
        shifts[pixel] = wp.vec4i(0)
        counts = wp.vec4i(0)
        sc = load_shading(scene, gb, pixel)
        if sc.valid == 0:
            return
        nq = temporal_neighbor(scene, prev_camera, prev_gb, sc)
        if nq.pixel == NO_PIXEL:
            return
        q = nq.pixel
        sq = nq.sh
        r = prev_reservoirs[q]
        Mq = cap_history(r.M, params.temporal_cap, c.M)
        key = rng_key(params.seed, params.frame, wp.uint32(STAGE_PT_TEMPORAL), wp.uint32(pixel))
        base = wp.uint32(params.sample) * wp.uint32(PT_TEMPORAL_DIMS_PER_SAMPLE)
        rays = int(0)
        failed = int(0)
        # ---- the history's sample, shifted into this domain
        fwd = ShiftResult()
        if holds_path(r) and r.W > 0.0:
            fwd = shift(scene, params, r, sc)
            rays += fwd.rays
            failed += 1 - fwd.valid
            counts += shift_counts(r, fwd)
        # The history's weight compares p_hat_q(x_q) / J M_q with p_hat_c(y) M_c; both are passed
        # times J (the weight is a ratio), so that a tiny J cannot overflow it to inf/inf.
        p_c_at_y = float(0.0)
        d_q_at_y = float(0.0)
        if fwd.valid != 0:
            p_c_at_y = luminance(fwd.r.F)
            d_q_at_y = luminance(r.F) * Mq
        # ---- the current sample, shifted into the previous domain (its density there)
        p_c = luminance(c.F)
        d_q_at_xc = float(0.0)
        if holds_path(c) and c.W > 0.0:
            back = shift(scene, params, c, sq)
            rays += back.rays
            counts += shift_counts(c, back)
            if back.valid != 0:
                d_q_at_xc = luminance(back.r.F) * back.J * Mq
        shifts[pixel] = counts
        if wp.static(drop_failed):
            if fwd.valid == 0:
                return
        s = ris_init()
        m_c = talbot_weight2(p_c * c.M, d_q_at_xc, CURRENT)
        s = ris_merge(s, m_c, p_c, 1.0, c.W, c.M, CURRENT, rng_uniform(key, base))
        m_q = talbot_weight2(p_c_at_y * c.M * fwd.J, d_q_at_y, HISTORY)
        s = ris_merge(s, m_q, p_c_at_y, fwd.J, r.W, Mq, HISTORY, rng_uniform(key, base + wp.uint32(1)))
        chosen = c
        if s.selected == HISTORY:
            chosen = with_origin(fwd.r, ORIGIN_TEMPORAL)
        reservoirs_out[pixel] = store(chosen, ris_finalize(s, 1.0))
        events[pixel] = stage_events(s, failed, rays)

    return temporal_kernel


temporal_kernel = make_temporal_kernel()
