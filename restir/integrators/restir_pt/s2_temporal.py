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
from ...device.rng import rng_key, rng_uniform
from ...device.scene_device import SceneDevice
from ...device.streams import PT_TEMPORAL_DIMS_PER_SAMPLE, STAGE_PT_TEMPORAL
from ...resampling.ris import cap_history, ris_finalize
from ..common.events import stage_events
from ..common.gbuffer import GBuffer
from ..common.reuse_domains import NO_PIXEL, temporal_neighbor
from ..common.shading import load_shading
from ..path_reuse.domain import domain_at
from ..path_reuse.params import PathReuseParams
from ..path_reuse.path_sample import PathReservoir, store
from ..path_reuse.reuse_pair import make_reuse_pair
from ..path_reuse.shift import shift_path
from .kernel_module import KERNEL_MODULE


def make_temporal_kernel(shift=shift_path, drop_failed: bool = False, module=None):
    """The temporal kernel over a shift function; drop_failed builds the mutation that drops a
    history whose shift failed (its M and its density in the current sample's weight)."""
    shift_in, _, temporal_pair, _ = make_reuse_pair(shift, module)

    @wp.kernel(module=module or KERNEL_MODULE)
    def temporal_kernel(offset: int, scene: SceneDevice, params: PathReuseParams, prev_camera: Camera, gb: GBuffer,
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
        dc = domain_at(sc, params)
        dq = domain_at(nq.sh, params)  # ReSTIR PT's pixels share the frame's parameters
        r = prev_reservoirs[q]
        Mq = cap_history(r.M, params.temporal_cap, c.M)
        key = rng_key(params.seed, params.frame, wp.uint32(STAGE_PT_TEMPORAL), wp.uint32(pixel))
        base = wp.uint32(params.sample) * wp.uint32(PT_TEMPORAL_DIMS_PER_SAMPLE)
        if wp.static(drop_failed):
            if shift_in(scene, r, Mq, c.M, dc).t.valid == 0:
                return
        # ---- the history's sample shifted here, and the current sample there (its density there)
        st = temporal_pair(scene, c, dc, r, Mq, dq, rng_uniform(key, base), rng_uniform(key, base + wp.uint32(1)))
        shifts[pixel] = st.tl.counts
        reservoirs_out[pixel] = store(st.chosen, ris_finalize(st.s, 1.0))
        events[pixel] = stage_events(st.s, st.tl.failed, st.tl.rays)

    return temporal_kernel


temporal_kernel = make_temporal_kernel()
