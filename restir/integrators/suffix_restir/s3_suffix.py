"""Stage "suffix": suffix generation and temporal reuse, one kernel
(docs/theory/suffix_restir.md#resampling-suffixes-conditioned-on-the-prefix).

A new suffix at the pixel's resampled prefix end, traced and resampled as a ReSTIR PT base path
whose start vertex is x_P: NEE at x_P first, then BSDF sampling, every event streamed
(w = p_hat(F_s), M = 1 per suffix); the suffix's own key (its replay seed) restarts the numbers at
x_P, and its throughput restarts at 1 there (docs/theory/suffix_restir.md#prefixes-and-suffixes). A
pixel without a prefix end keeps an empty reservoir of M = 0. With temporal reuse (and a previous
frame) the new suffix, kept in registers, is then resampled with the previous frame's final suffix
reservoir of the pixel that saw this primary hit: the two suffix domains are the two pixels'
resampled prefix ends (this frame's, and the previous pixel's of the previous frame); each suffix is
shifted into the other's domain (ReSTIR PT's shift from the prefix end, with the destination's
length budget), generalized balance MIS over the two (pairwise with K = 1), the history's M capped
at suffix_cap (absolute) before any weight. The history is a technique when the previous pixel had a
primary hit like this one and a prefix end (geometry only).
Reads: scene, G-buffers (this frame's, previous), previous camera, prefixes and prefix G-buffers
(this frame's resampled, previous), the previous final suffix reservoirs.
Writes: suffix reservoirs (another buffer), shift counts, events.
"""
import warp as wp

from ...device.camera import Camera
from ...device.rng import hash_combine, rng_key, rng_uniform
from ...device.scene_device import SceneDevice
from ...device.streams import PT_TEMPORAL_DIMS_PER_SAMPLE, STAGE_SR_SUFFIX, STAGE_SR_SUFFIX_RIS, STAGE_SR_SUFFIX_TEMPORAL
from ...resampling.ris import cap_history, ris_finalize, ris_init
from ..common.events import EventCounts, PassCounts, packed_counts, packed_events, stage_events
from ..common.gbuffer import GBuffer
from ..common.reuse_domains import NO_PIXEL, temporal_neighbor
from ..common.shading import load_shading
from ..path_reuse.base_path import EVENTS_PER_PATH, BasePath, trace_base_path
from ..path_reuse.path_sample import NO_RC, PathReservoir, empty_path, holds_path, rc_length, store
from ..path_reuse.reuse_pair import make_reuse_pair
from ..path_reuse.shift import SHIFT_INLINED
from .domains import Domain, load_domain
from .params import KERNEL_MODULE, SRParams
from .prefix import PrefixReservoir, prefix_length

SUFFIX_MUTATIONS = ("rc_index_at_prefix_length", "suffix_seed_not_reset", "prefix_thp_in_target")


@wp.struct
class NewSuffix:
    r: PathReservoir
    s: BasePath


@wp.func
def new_suffix(scene: SceneDevice, params: SRParams, d: Domain, pixel: int) -> NewSuffix:
    """The pixel's new suffix in its domain d (streaming RIS over `candidates` suffixes)."""
    out = NewSuffix()
    acc = BasePath()
    acc.s = ris_init()
    acc.r = empty_path()
    out.r = empty_path()
    if d.sh.valid != 0:
        path_key = rng_key(params.pt.seed, params.pt.frame, wp.uint32(STAGE_SR_SUFFIX), wp.uint32(pixel))
        ris_key = rng_key(params.pt.seed, params.pt.frame, wp.uint32(STAGE_SR_SUFFIX_RIS), wp.uint32(pixel))
        for c in range(params.pt.candidates):
            path_id = wp.uint32(params.pt.sample * params.pt.candidates + c)
            acc = trace_base_path(scene, d.params, d.sh, hash_combine(path_key, path_id), hash_combine(ris_key, path_id),
                                  c * EVENTS_PER_PATH, acc)
        f = ris_finalize(acc.s, 1.0)
        f.M = float(params.pt.candidates)
        out.r = store(acc.r, f)
    out.s = acc
    return out


def make_suffix_kernel(mutation: str = "none"):
    """The suffix kernel; a mutation builds a fault-injected variant
    (docs/validation.md#power-checks-the-mutation-table):
    rc_index_at_prefix_length (the rc vertex recorded at index P, as if counted from the primary
    hit: the defect S2), suffix_seed_not_reset (the replay seed stored is the prefix's, not the one
    the suffix was traced with: replay does not restart at x_P), prefix_thp_in_target
    (the suffix's integrand and target scaled by the prefix's, W divided by it: F W unchanged here,
    but the target is no longer the one shifts evaluate:
    docs/theory/suffix_restir.md#prefixes-and-suffixes)."""
    module = KERNEL_MODULE if mutation == "none" else f"suffix_restir_{mutation}"
    rc_at_prefix = mutation == "rc_index_at_prefix_length"
    seed_not_reset = mutation == "suffix_seed_not_reset"
    thp_in_target = mutation == "prefix_thp_in_target"
    _, _, temporal_pair, _ = make_reuse_pair(SHIFT_INLINED)  # inlined: two calls (path_reuse/shift.py)

    @wp.kernel(module=module)
    def suffix_kernel(offset: int, scene: SceneDevice, params: SRParams, temporal: int, camera: Camera,
                      prev_camera: Camera, gb: GBuffer, prev_gb: GBuffer, prefixes: wp.array(dtype=PrefixReservoir),
                      prefix_gb: GBuffer,
                      prev_prefixes: wp.array(dtype=PrefixReservoir), prev_prefix_gb: GBuffer,
                      prev_reservoirs: wp.array(dtype=PathReservoir), reservoirs: wp.array(dtype=PathReservoir),
                      shifts: wp.array(dtype=PassCounts), events: wp.array(dtype=EventCounts)):
        pixel = wp.tid() + offset
        dc = load_domain(scene, params, prefixes, prefix_gb, pixel)
        fresh = new_suffix(scene, params, dc, pixel)
        c = fresh.r
        if wp.static(rc_at_prefix):
            if holds_path(c) and rc_length(c.flags) != NO_RC:
                c.flags = (c.flags & ~(255 << 8)) | (prefix_length(prefixes[pixel].flags) << 8)
        if wp.static(seed_not_reset):
            c.seed = prefixes[pixel].seed
        if wp.static(thp_in_target):
            if holds_path(c) and prefixes[pixel].p_hat > 0.0:
                c.F = c.F * prefixes[pixel].p_hat
                c.W = c.W / prefixes[pixel].p_hat
        reservoirs[pixel] = c
        shifts[pixel] = packed_counts(wp.vec4i(0))
        events[pixel] = packed_events(stage_events(fresh.s.s, 0, fresh.s.rays))
        if temporal == 0 or dc.sh.valid == 0:
            return
        # ---- temporal reuse of the previous frame's final suffix of the pixel that saw this hit
        nq = temporal_neighbor(scene, scene, camera, prev_camera, prev_gb, load_shading(scene, gb, pixel), pixel)
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
        st = temporal_pair(scene, scene, c, dc, r, Mq, dq, rng_uniform(key, base),
                           rng_uniform(key, base + wp.uint32(1)))
        shifts[pixel] = packed_counts(st.tl.counts)
        reservoirs[pixel] = store(st.chosen, ris_finalize(st.s, 1.0))
        ev = stage_events(st.s, st.tl.failed, st.tl.rays)
        events[pixel] = packed_events(ev + wp.vec4i(fresh.s.s.nonfinite, fresh.s.s.zero, 0, fresh.s.rays))

    return suffix_kernel


suffix_kernel = make_suffix_kernel()
