"""Stage 2, temporal reuse: the pixel's new reservoir with last frame's final reservoir where
this pixel's primary hit was seen, by generalized balance (Talbot) MIS over the two techniques
(docs/theory/restir_pt.md#temporal-reuse). The previous confidence is capped to temporal_cap x the current one before
any weight is computed (cap_history). Both samples are shifted: the current one into the
previous domain (its density there, for its own weight) and the history's into this one.
The previous domain is the previous primary hit seen by the previous camera, in the previous
frame's scene (`prev_scene`: the current one when nothing moved), where the current sample is
replayed for its density there. On an animated scene only the replay shift is accepted
(ReSTIR PT's motion_refusal): the others keep a path's suffix after its reconnection vertex as
cached radiance, which would have to be traced again in each frame's scene. The replay is done
inline in this pass (no separate retrace pass): the same function runs for both directions with
the same seeds, so the two passes of
the official code cannot disagree here by construction.

Two kernels run it. The shipped one, `trace_temporal_kernel`, is stage 1 and this stage fused:
the pixel's new reservoir (s1_initial.initial_reservoir) stays in registers, so no buffer holds
it between the stages and the reuse passes after this one can write into the history's buffer,
which nothing reads once this kernel has run (76 B per pixel fewer; ping-pong all the same: the
kernel reads the history, written a frame earlier, and writes the current buffer, which it never
reads). With temporal = 0 (the first frame, or temporal reuse off) it is stage 1 alone.
`stages.split` runs the stages as two kernels instead, each timed, with the third buffer:
the same functions in the same order, so the images are bit for bit the same.
Reads: scene, G-buffer, previous G-buffer and camera, previous final reservoirs (and, split, the
reservoirs; fused, stage 1's emission and filter weights). Writes: reservoirs (split:
reservoirs_out), shift counts, events (fused, with direct=nee: stage 1's direct light).
"""
import warp as wp

from ...device.camera import Camera
from ...device.rng import rng_key, rng_uniform
from ...device.scene_device import SceneDevice
from ...device.streams import PT_TEMPORAL_DIMS_PER_SAMPLE, STAGE_PT_TEMPORAL
from ...resampling.ris import cap_history, ris_finalize
from ..common.events import EventCounts, PassCounts, packed_counts, packed_events, stage_events
from ..common.gbuffer import GBuffer
from ..common.reuse_domains import NO_PIXEL, temporal_neighbor
from ..common.shading import Shading, load_shading
from ..path_reuse.domain import domain_at
from ..path_reuse.params import PathReuseParams
from ..path_reuse.path_sample import PathReservoir, sample_output, store
from ..path_reuse.reuse_pair import make_reuse_pair
from ..path_reuse.shift import SHIFT_INLINED
from .kernel_module import KERNEL_MODULE, SPLIT_MODULE
from .s1_initial import make_initial_reservoir, store_direct

_built: dict = {}


def make_temporal_reuse(shift=SHIFT_INLINED, drop_failed: bool = False, module=None):
    """The stage's work for one pixel as a function: (reservoir, shift counts, events, expected
    output) from the pixel's new reservoir c and shading point sc; the expected output is the
    pass's (Reuse.L), or c's own F W where no history was resampled. drop_failed builds the
    mutation that drops a history whose shift failed (its M and its density in the current sample's weight). Built once
    per (shift, drop_failed, module): the split and the fused kernels call the same function."""
    if (shift, drop_failed, module) in _built:
        return _built[shift, drop_failed, module]
    shift_in, _, temporal_pair, _ = make_reuse_pair(shift, module)

    @wp.func(module=module or KERNEL_MODULE)
    def temporal_reuse(scene: SceneDevice, prev_scene: SceneDevice, params: PathReuseParams, camera: Camera,
                       prev_camera: Camera, prev_gb: GBuffer, prev_reservoirs: wp.array(dtype=PathReservoir),
                       c: PathReservoir, sc: Shading, pixel: int):
        none = wp.vec4i(0)
        own = sample_output(c)
        if sc.valid == 0:
            return c, none, none, own
        nq = temporal_neighbor(prev_scene, prev_scene, camera, prev_camera, prev_gb, sc, pixel)
        if nq.pixel == NO_PIXEL:
            return c, none, none, own
        q = nq.pixel
        dc = domain_at(sc, params)
        dq = domain_at(nq.sh, params)  # ReSTIR PT's pixels share the frame's parameters
        r = prev_reservoirs[q]
        Mq = cap_history(r.M, params.temporal_cap, c.M)
        key = rng_key(params.seed, params.frame, wp.uint32(STAGE_PT_TEMPORAL), wp.uint32(pixel))
        base = wp.uint32(params.sample) * wp.uint32(PT_TEMPORAL_DIMS_PER_SAMPLE)
        if wp.static(drop_failed):
            if shift_in(scene, r, Mq, c.M, dc).t.valid == 0:
                return c, none, none, own
        # ---- the history's sample shifted here, and the current sample there (its density there)
        st = temporal_pair(scene, prev_scene, c, dc, r, Mq, dq, rng_uniform(key, base),
                           rng_uniform(key, base + wp.uint32(1)))
        return (store(st.chosen, ris_finalize(st.s, 1.0)), st.tl.counts, stage_events(st.s, st.tl.failed, st.tl.rays),
                st.L)

    _built[shift, drop_failed, module] = temporal_reuse
    return temporal_reuse


def make_temporal_kernel(shift=SHIFT_INLINED, drop_failed: bool = False, module=None):
    """The split temporal kernel (`stages.split`) over a shift function."""
    temporal_reuse = make_temporal_reuse(shift, drop_failed, module)

    @wp.kernel(module=module or SPLIT_MODULE)
    def temporal_kernel(offset: int, scene: SceneDevice, prev_scene: SceneDevice, params: PathReuseParams,
                        camera: Camera, prev_camera: Camera, gb: GBuffer, prev_gb: GBuffer, prev_reservoirs: wp.array(dtype=PathReservoir),
                        reservoirs: wp.array(dtype=PathReservoir), reservoirs_out: wp.array(dtype=PathReservoir),
                        expected: wp.array(dtype=wp.vec3), shifts: wp.array(dtype=PassCounts),
                        events: wp.array(dtype=EventCounts)):
        pixel = wp.tid() + offset
        r, n, ev, L = temporal_reuse(scene, prev_scene, params, camera, prev_camera, prev_gb, prev_reservoirs,
                                     reservoirs[pixel],
                                     load_shading(scene, gb, pixel), pixel)
        reservoirs_out[pixel] = r
        if params.expected_out != 0:
            expected[pixel] = L
        shifts[pixel] = packed_counts(n)
        events[pixel] = packed_events(ev)

    return temporal_kernel


def make_trace_temporal_kernel(shift=SHIFT_INLINED, drop_failed: bool = False, m_per_event: bool = False,
                               module=None):
    """The shipped kernel, stages 1 and 2 fused, over a shift function; the mutations as in
    make_temporal_reuse and s1_initial.make_initial_reservoir."""
    temporal_reuse = make_temporal_reuse(shift, drop_failed, module)
    initial = make_initial_reservoir(m_per_event)

    @wp.kernel(module=module or KERNEL_MODULE)
    def trace_temporal_kernel(offset: int, scene: SceneDevice, prev_scene: SceneDevice, params: PathReuseParams,
                              temporal: int,
                              camera: Camera, prev_camera: Camera, gb: GBuffer, prev_gb: GBuffer,
                              prev_reservoirs: wp.array(dtype=PathReservoir), emission: wp.array(dtype=wp.vec3),
                              primary_weight: wp.array(dtype=float), reservoirs: wp.array(dtype=PathReservoir),
                              direct: wp.array(dtype=wp.vec3), expected: wp.array(dtype=wp.vec3),
                              shifts: wp.array(dtype=PassCounts), events: wp.array(dtype=EventCounts)):
        pixel = wp.tid() + offset
        sc = load_shading(scene, gb, pixel)
        c, ev, d = initial(scene, params, sc, pixel)
        store_direct(params, pixel, d, emission, primary_weight, direct)  # stage 1's own output
        n = wp.vec4i(0)
        L = sample_output(c)
        if temporal != 0:
            c, n, ev_t, L = temporal_reuse(scene, prev_scene, params, camera, prev_camera, prev_gb, prev_reservoirs, c,
                                           sc, pixel)
            ev = ev + ev_t
        reservoirs[pixel] = c
        if params.expected_out != 0:  # the last pass (no spatial reuse): its expected output
            expected[pixel] = L
        shifts[pixel] = packed_counts(n)
        events[pixel] = packed_events(ev)

    return trace_temporal_kernel


temporal_kernel = make_temporal_kernel()
trace_temporal_kernel = make_trace_temporal_kernel()
