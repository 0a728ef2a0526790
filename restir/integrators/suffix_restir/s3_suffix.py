"""Stage "suffix": a new suffix at each pixel's resampled prefix end (ALGORITHMS.md 5.4 step 5,
5.5), traced and resampled as a ReSTIR PT base path whose start vertex is x_P: NEE at x_P first,
then BSDF sampling, every event streamed (w = p_hat(F_s), M = 1 per suffix); the suffix's own key
(its replay seed) restarts the numbers at x_P (6 item 11), and its throughput restarts at 1 there
(6 item 12). A pixel without a prefix end keeps an empty reservoir of M = 0.
Reads: scene, prefixes, prefix G-buffer. Writes: suffix reservoirs, events.
"""
import warp as wp

from ...device.rng import hash_combine, rng_key
from ...device.scene_device import SceneDevice
from ...device.streams import STAGE_SR_SUFFIX, STAGE_SR_SUFFIX_RIS
from ...resampling.ris import ris_finalize, ris_init
from ..common.events import stage_events
from ..common.gbuffer import GBuffer
from ..restir_pt.base_path import BasePath, trace_base_path
from ..restir_pt.path_sample import NO_RC, PathReservoir, empty_path, holds_path, rc_length, store
from ..restir_pt.s1_initial import EVENTS_PER_PATH
from .domains import load_domain
from .params import KERNEL_MODULE, SRParams
from .prefix import PrefixReservoir, prefix_length


def make_suffix_kernel(mutation: str = "none"):
    """The suffix kernel; a mutation builds a fault-injected variant (TESTING.md 5.11):
    rc_index_at_prefix_length (the rc vertex recorded at index P, as if counted from the primary
    hit: the defect S2), suffix_seed_not_reset (the replay seed stored is the prefix's, not the one
    the suffix was traced with: replay does not restart at x_P, 6 item 11), prefix_thp_in_target
    (the suffix's integrand and target scaled by the prefix's, W divided by it: F W unchanged here,
    but the target is no longer the one shifts evaluate, 6 item 12)."""
    module = KERNEL_MODULE if mutation == "none" else f"suffix_restir_{mutation}"
    rc_at_prefix = mutation == "rc_index_at_prefix_length"
    seed_not_reset = mutation == "suffix_seed_not_reset"
    thp_in_target = mutation == "prefix_thp_in_target"

    @wp.kernel(module=module)
    def suffix_kernel(offset: int, scene: SceneDevice, params: SRParams, prefixes: wp.array(dtype=PrefixReservoir),
                      prefix_gb: GBuffer, reservoirs: wp.array(dtype=PathReservoir), events: wp.array(dtype=wp.vec4i)):
        pixel = wp.tid() + offset
        acc = BasePath()
        acc.s = ris_init()
        acc.r = empty_path()
        out = empty_path()
        d = load_domain(scene, params, prefixes, prefix_gb, pixel)
        if d.sh.valid != 0:
            path_key = rng_key(params.pt.seed, params.pt.frame, wp.uint32(STAGE_SR_SUFFIX), wp.uint32(pixel))
            ris_key = rng_key(params.pt.seed, params.pt.frame, wp.uint32(STAGE_SR_SUFFIX_RIS), wp.uint32(pixel))
            for c in range(params.pt.candidates):
                path_id = wp.uint32(params.pt.sample * params.pt.candidates + c)
                acc = trace_base_path(scene, d.params, d.sh, hash_combine(path_key, path_id),
                                      hash_combine(ris_key, path_id), c * EVENTS_PER_PATH, acc)
            f = ris_finalize(acc.s, 1.0)
            f.M = float(params.pt.candidates)
            out = store(acc.r, f)
            if wp.static(rc_at_prefix):
                if holds_path(out) and rc_length(out.flags) != NO_RC:
                    out.flags = (out.flags & ~(255 << 8)) | (prefix_length(prefixes[pixel].flags) << 8)
            if wp.static(seed_not_reset):
                out.seed = prefixes[pixel].seed
            if wp.static(thp_in_target):
                if holds_path(out) and prefixes[pixel].p_hat > 0.0:
                    out.F = out.F * prefixes[pixel].p_hat
                    out.W = out.W / prefixes[pixel].p_hat
        reservoirs[pixel] = out
        events[pixel] = stage_events(acc.s, 0, acc.rays)

    return suffix_kernel


SUFFIX_MUTATIONS = ("rc_index_at_prefix_length", "suffix_seed_not_reset", "prefix_thp_in_target")
suffix_kernel = make_suffix_kernel()
