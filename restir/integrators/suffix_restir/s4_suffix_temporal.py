"""Stage "suffix_temporal" (ALGORITHMS.md 5.7): the pixel's new suffix with the previous frame's
final suffix reservoir of the pixel that saw this primary hit. The two suffix domains are the
two pixels' resampled prefix ends (this frame's, and the previous pixel's of the previous frame);
each suffix is shifted into the other's domain (ReSTIR PT's shift from the prefix end, with the
destination's length budget), generalized balance MIS over the two (pairwise with K = 1), the
history's M capped at suffix_cap (absolute, 5.8) before any weight. The history is a technique
when the previous pixel had a primary hit like this one and a prefix end (geometry only).
Reads: G-buffers (this frame's, previous), previous camera, prefixes and prefix G-buffers (this
frame's resampled, previous), suffix reservoirs, previous final suffix reservoirs.
Writes: suffix reservoirs (other buffer), shift counts, events.
"""
import warp as wp

from ...device.camera import Camera
from ...device.color import luminance
from ...device.rng import rng_key, rng_uniform
from ...device.scene_device import SceneDevice
from ...device.streams import PT_TEMPORAL_DIMS_PER_SAMPLE, STAGE_SR_SUFFIX_TEMPORAL
from ...resampling.mis import talbot_weight2
from ...resampling.ris import cap_history, ris_finalize, ris_init, ris_merge
from ..common.events import stage_events
from ..common.gbuffer import GBuffer
from ..common.reuse_domains import NO_PIXEL, temporal_neighbor
from ..common.shading import load_shading
from ..restir_pt.path_sample import ORIGIN_TEMPORAL, PathReservoir, store, with_origin
from ..restir_pt.reuse_pair import ShiftTally, make_reuse_pair, tally
from ..restir_pt.shift import shift_path
from .domains import load_domain
from .params import KERNEL_MODULE, SRParams
from .prefix import PrefixReservoir

CURRENT = wp.constant(0)
HISTORY = wp.constant(1)


def make_suffix_temporal_kernel(shift=shift_path, module=None):
    shift_in, shift_out = make_reuse_pair(shift, module)

    @wp.kernel(module=module or KERNEL_MODULE)
    def suffix_temporal_kernel(offset: int, scene: SceneDevice, params: SRParams, prev_camera: Camera, gb: GBuffer,
                               prev_gb: GBuffer, prefixes: wp.array(dtype=PrefixReservoir), prefix_gb: GBuffer,
                               prev_prefixes: wp.array(dtype=PrefixReservoir), prev_prefix_gb: GBuffer,
                               prev_reservoirs: wp.array(dtype=PathReservoir),
                               reservoirs: wp.array(dtype=PathReservoir), reservoirs_out: wp.array(dtype=PathReservoir),
                               shifts: wp.array(dtype=wp.vec4i), events: wp.array(dtype=wp.vec4i)):
        pixel = wp.tid() + offset
        c = reservoirs[pixel]
        reservoirs_out[pixel] = c
        events[pixel] = wp.vec4i(0)
        shifts[pixel] = wp.vec4i(0)
        dc = load_domain(scene, params, prefixes, prefix_gb, pixel)
        if dc.sh.valid == 0:
            return
        nq = temporal_neighbor(scene, prev_camera, prev_gb, load_shading(scene, gb, pixel))
        if nq.pixel == NO_PIXEL:
            return
        q = nq.pixel
        dq = load_domain(scene, params, prev_prefixes, prev_prefix_gb, q)
        if dq.sh.valid == 0:
            return
        r = prev_reservoirs[q]
        Mq = cap_history(r.M, params.suffix_cap, 1.0)
        hist = shift_in(scene, dc.params, r, Mq, c.M, dc.sh)
        cur = shift_out(scene, dq.params, c, Mq, dq.sh)
        tl = tally(tally(ShiftTally(), r, hist.t, hist.tried, 1), c, cur.t, cur.tried, 0)
        shifts[pixel] = tl.counts
        key = rng_key(params.pt.seed, params.pt.frame, wp.uint32(STAGE_SR_SUFFIX_TEMPORAL), wp.uint32(pixel))
        base = wp.uint32(params.pt.sample) * wp.uint32(PT_TEMPORAL_DIMS_PER_SAMPLE)
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

    return suffix_temporal_kernel


suffix_temporal_kernel = make_suffix_temporal_kernel()
