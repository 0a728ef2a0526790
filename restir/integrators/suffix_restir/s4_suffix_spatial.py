"""Stage "suffix_spatial"
(docs/theory/suffix_restir.md#resampling-suffixes-conditioned-on-the-prefix): pairwise MIS over the
pixel's suffix and those of k neighbours drawn in a screen disk of the suffix spatial radius, each
in its own suffix domain (the neighbour's resampled prefix end). A neighbour is a technique when it
is on screen and has a prefix end (geometry only; the official code tests no normal or depth for
suffix reuse). Shifts as in suffix temporal reuse; ping-pong rounds.
Reads: scene, prefixes, prefix G-buffer, suffix reservoirs. Writes: suffix reservoirs (other
buffer), shift counts, events.
"""
import warp as wp

from ...device.rng import rng_key, rng_uniform, rng_uniform2
from ...device.scene_device import SceneDevice
from ...device.streams import (DI_SPATIAL_DIM_CANONICAL, DI_SPATIAL_DIM_OFFSET, DI_SPATIAL_DIM_SELECT,
                               DI_SPATIAL_DIMS_PER_NEIGHBOR, DI_SPATIAL_DIMS_PER_SAMPLE, STAGE_SR_SUFFIX_SPATIAL)
from ...resampling.mis import pairwise_normalization
from ...resampling.ris import ris_finalize
from ..common.events import EventCounts, PassCounts, packed_counts, packed_events, stage_events
from ..common.gbuffer import GBuffer
from ..common.reuse_domains import NO_PIXEL, spatial_neighbor
from ..path_reuse.path_sample import PathReservoir, store
from ..path_reuse.reuse_pair import make_reuse_pair, spatial_canonical, spatial_start
from ..path_reuse.shift import SHIFT_INLINED
from .domains import load_domain
from .params import KERNEL_MODULE, SRParams
from .prefix import PrefixReservoir


def make_suffix_spatial_kernel(shift=SHIFT_INLINED, module=None):
    _, _, _, spatial_step = make_reuse_pair(shift, module)

    @wp.kernel(module=module or KERNEL_MODULE)
    def suffix_spatial_kernel(offset: int, scene: SceneDevice, params: SRParams, width: int, height: int,
                              prefixes: wp.array(dtype=PrefixReservoir), prefix_gb: GBuffer,
                              reservoirs_in: wp.array(dtype=PathReservoir), reservoirs_out: wp.array(dtype=PathReservoir),
                              shifts: wp.array(dtype=PassCounts), events: wp.array(dtype=EventCounts)):
        pixel = wp.tid() + offset
        c = reservoirs_in[pixel]
        events[pixel] = packed_events(wp.vec4i(0))
        shifts[pixel] = packed_counts(wp.vec4i(0))
        dc = load_domain(scene, params, prefixes, prefix_gb, pixel)
        if dc.sh.valid == 0:
            reservoirs_out[pixel] = c
            return
        key = rng_key(params.pt.seed, params.pt.frame, wp.uint32(STAGE_SR_SUFFIX_SPATIAL + params.pt.spatial_round),
                      wp.uint32(pixel))
        base = wp.uint32(params.pt.sample) * wp.uint32(DI_SPATIAL_DIMS_PER_SAMPLE)
        st = spatial_start(c, params.pt.spatial_k)
        for j in range(params.pt.spatial_k):
            dim = base + wp.uint32(j * DI_SPATIAL_DIMS_PER_NEIGHBOR)
            n = spatial_neighbor(rng_uniform2(key, dim + wp.uint32(DI_SPATIAL_DIM_OFFSET)), pixel, width, height,
                                 params.pt.spatial_radius)
            if n == NO_PIXEL:
                continue
            dn = load_domain(scene, params, prefixes, prefix_gb, n)
            if dn.sh.valid == 0:
                continue
            st = spatial_step(st, scene, c, dc, reservoirs_in[n], dn, j,
                              rng_uniform(key, dim + wp.uint32(DI_SPATIAL_DIM_SELECT)))
        st = spatial_canonical(st, c, rng_uniform(key, base + wp.uint32(DI_SPATIAL_DIM_CANONICAL)))
        reservoirs_out[pixel] = store(st.chosen, ris_finalize(st.s, pairwise_normalization(st.mis)))
        events[pixel] = packed_events(stage_events(st.s, st.tl.failed, st.tl.rays))
        shifts[pixel] = packed_counts(st.tl.counts)

    return suffix_spatial_kernel


suffix_spatial_kernel = make_suffix_spatial_kernel()
