"""Stage 4, spatial reuse: pairwise MIS over the pixel and k neighbours (ALGORITHMS.md 4.3).

Neighbours: k pixels drawn uniformly in a disk of `spatial_radius` pixels, kept when on screen,
with a primary hit and geometrically similar (G-buffers only, never reservoir contents). For
each, its sample is shifted here and this pixel's sample there (the canonical weight's density):
two shifts, each a replay to rcPrev and one visibility ray (done inline: see s2_temporal.py).
Own-domain targets are the stored integrands (4.7). Reads: scene, G-buffer, reservoirs_in.
Writes: reservoirs_out (a different buffer: ping-pong), events.
"""
import warp as wp

from ...device.rng import rng_key, rng_uniform, rng_uniform2
from ...device.scene_device import SceneDevice
from ...device.streams import (DI_SPATIAL_DIM_CANONICAL, DI_SPATIAL_DIM_OFFSET, DI_SPATIAL_DIM_SELECT,
                               DI_SPATIAL_DIMS_PER_NEIGHBOR, DI_SPATIAL_DIMS_PER_SAMPLE, STAGE_PT_SPATIAL)
from ...resampling.mis import pairwise_normalization
from ...resampling.ris import ris_finalize
from ..common.events import EventCounts, PassCounts, packed_counts, packed_events, stage_events
from ..common.gbuffer import GBuffer
from ..common.reuse_domains import NO_PIXEL, spatial_technique
from ..common.shading import load_shading
from ..path_reuse.domain import domain_at
from ..path_reuse.params import PathReuseParams
from ..path_reuse.path_sample import PathReservoir, store
from ..path_reuse.reuse_pair import make_reuse_pair, spatial_canonical, spatial_start
from ..path_reuse.shift import shift_path
from .kernel_module import KERNEL_MODULE


def make_spatial_kernel(shift=shift_path, drop_failed: bool = False, module=None):
    """The spatial kernel over a shift function; drop_failed builds the mutation that leaves
    neighbours whose shift failed out of the technique set (V, M and the canonical weight)."""
    shift_in, _, _, spatial_neighbor = make_reuse_pair(shift, module)

    @wp.kernel(module=module or KERNEL_MODULE)
    def spatial_kernel(offset: int, scene: SceneDevice, params: PathReuseParams, width: int, height: int, gb: GBuffer,
                       reservoirs_in: wp.array(dtype=PathReservoir), reservoirs_out: wp.array(dtype=PathReservoir),
                       shifts: wp.array(dtype=PassCounts), events: wp.array(dtype=EventCounts)):
        pixel = wp.tid() + offset
        c = reservoirs_in[pixel]
        events[pixel] = packed_events(wp.vec4i(0))
        shifts[pixel] = packed_counts(wp.vec4i(0))
        sc = load_shading(scene, gb, pixel)
        if sc.valid == 0:
            reservoirs_out[pixel] = c
            return
        key = rng_key(params.seed, params.frame, wp.uint32(STAGE_PT_SPATIAL + params.spatial_round), wp.uint32(pixel))
        base = wp.uint32(params.sample) * wp.uint32(DI_SPATIAL_DIMS_PER_SAMPLE)
        dc = domain_at(sc, params)  # ReSTIR PT's pixels share the frame's parameters
        st = spatial_start(c, params.spatial_k)
        for j in range(params.spatial_k):
            dim = base + wp.uint32(j * DI_SPATIAL_DIMS_PER_NEIGHBOR)
            nb = spatial_technique(scene, gb, rng_uniform2(key, dim + wp.uint32(DI_SPATIAL_DIM_OFFSET)), pixel, width,
                                   height, params.spatial_radius, sc)
            if nb.pixel == NO_PIXEL:
                continue
            r = reservoirs_in[nb.pixel]
            if wp.static(drop_failed):
                if shift_in(scene, r, r.M, c.M, dc).t.valid == 0:
                    continue
            # ---- the neighbour's sample here, and this pixel's sample there
            st = spatial_neighbor(st, scene, c, dc, r, domain_at(nb.sh, params), j,
                                  rng_uniform(key, dim + wp.uint32(DI_SPATIAL_DIM_SELECT)))
        st = spatial_canonical(st, c, rng_uniform(key, base + wp.uint32(DI_SPATIAL_DIM_CANONICAL)))
        reservoirs_out[pixel] = store(st.chosen, ris_finalize(st.s, pairwise_normalization(st.mis)))
        events[pixel] = packed_events(stage_events(st.s, st.tl.failed, st.tl.rays))
        shifts[pixel] = packed_counts(st.tl.counts)

    return spatial_kernel


spatial_kernel = make_spatial_kernel()
