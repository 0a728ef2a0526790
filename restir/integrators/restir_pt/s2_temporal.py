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
from .params import KERNEL_MODULE, PTRParams
from .path_sample import ORIGIN_TEMPORAL, PathReservoir, store, with_origin
from .reuse_pair import ShiftTally, make_reuse_pair, tally
from .shift import shift_path

CURRENT = wp.constant(0)
HISTORY = wp.constant(1)


def make_temporal_kernel(shift=shift_path, drop_failed: bool = False, module=None):
    """The temporal kernel over a shift function; drop_failed builds the mutation that drops a
    history whose shift failed (its M and its density in the current sample's weight)."""
    shift_in, shift_out = make_reuse_pair(shift, module)

    @wp.kernel(module=module or KERNEL_MODULE)
    def temporal_kernel(offset: int, scene: SceneDevice, params: PTRParams, prev_camera: Camera, gb: GBuffer,
                        prev_gb: GBuffer, prev_reservoirs: wp.array(dtype=PathReservoir),
                        reservoirs: wp.array(dtype=PathReservoir), reservoirs_out: wp.array(dtype=PathReservoir),
                        shifts: wp.array(dtype=wp.vec4i), events: wp.array(dtype=wp.vec4i)):
        pixel = wp.tid() + offset
        c = reservoirs[pixel]
        reservoirs_out[pixel] = c
        events[pixel] = wp.vec4i(0)
        shifts[pixel] = wp.vec4i(0)
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
        # ---- the history's sample shifted here, and the current sample there (its density there)
        hist = shift_in(scene, params, r, Mq, c.M, sc)
        cur = shift_out(scene, params, c, Mq, sq)
        tl = tally(tally(ShiftTally(), r, hist.t, hist.tried, 1), c, cur.t, cur.tried, 0)
        shifts[pixel] = tl.counts
        if wp.static(drop_failed):
            if hist.t.valid == 0:
                return
        s = ris_init()
        p_c = luminance(c.F)
        s = ris_merge(s, talbot_weight2(p_c * c.M, cur.d_i, CURRENT), p_c, 1.0, c.W, c.M, CURRENT,
                      rng_uniform(key, base))
        s = ris_merge(s, talbot_weight2(hist.d_c, hist.d_i, HISTORY), hist.p_c, hist.t.J, r.W, Mq, HISTORY,
                      rng_uniform(key, base + wp.uint32(1)))
        chosen = c
        if s.selected == HISTORY:
            chosen = with_origin(hist.t.r, ORIGIN_TEMPORAL)
        reservoirs_out[pixel] = store(chosen, ris_finalize(s, 1.0))
        events[pixel] = stage_events(s, tl.failed, tl.rays)

    return temporal_kernel


temporal_kernel = make_temporal_kernel()
