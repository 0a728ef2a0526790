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
from ...device.rng import rng_key, rng_uniform
from ...device.scene_device import SceneDevice
from ...device.streams import PT_TEMPORAL_DIMS_PER_SAMPLE, STAGE_SR_SUFFIX_TEMPORAL
from ...resampling.ris import cap_history, ris_finalize
from ..common.events import stage_events
from ..common.gbuffer import GBuffer
from ..common.reuse_domains import NO_PIXEL, temporal_neighbor
from ..common.shading import load_shading
from ..restir_pt.path_sample import PathReservoir, store
from ..restir_pt.reuse_pair import make_reuse_pair
from ..restir_pt.shift import shift_path
from .domains import load_domain
from .params import KERNEL_MODULE, SRParams
from .prefix import PrefixReservoir


def make_suffix_temporal_kernel(shift=shift_path, module=None):
    _, _, temporal_pair, _ = make_reuse_pair(shift, module)

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
        key = rng_key(params.pt.seed, params.pt.frame, wp.uint32(STAGE_SR_SUFFIX_TEMPORAL), wp.uint32(pixel))
        base = wp.uint32(params.pt.sample) * wp.uint32(PT_TEMPORAL_DIMS_PER_SAMPLE)
        st = temporal_pair(scene, c, dc.params, dc.sh, r, Mq, dq.params, dq.sh, rng_uniform(key, base),
                           rng_uniform(key, base + wp.uint32(1)))
        shifts[pixel] = st.tl.counts
        reservoirs_out[pixel] = store(st.chosen, ris_finalize(st.s, 1.0))
        events[pixel] = stage_events(st.s, st.tl.failed, st.tl.rays)

    return suffix_temporal_kernel


suffix_temporal_kernel = make_suffix_temporal_kernel()
