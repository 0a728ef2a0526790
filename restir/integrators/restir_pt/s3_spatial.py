"""Stage 3, spatial reuse: pairwise MIS over the pixel and k neighbours (ALGORITHMS.md 4.3).

Neighbours: k pixels drawn uniformly in a disk of `spatial_radius` pixels, kept when on screen,
with a primary hit and geometrically similar (G-buffers only, never reservoir contents). For
each, its sample is shifted here and this pixel's sample there (the canonical weight's density):
two shifts, each a replay to rcPrev and one visibility ray (done inline: see s2_temporal.py).
Own-domain targets are the stored integrands (4.7). Reads: scene, G-buffer, reservoirs_in.
Writes: reservoirs_out (a different buffer: ping-pong), events.
"""
import warp as wp

from ...device.color import luminance
from ...device.rng import rng_key, rng_uniform, rng_uniform2
from ...device.scene_device import SceneDevice
from ...device.streams import (DI_SPATIAL_DIM_CANONICAL, DI_SPATIAL_DIM_OFFSET, DI_SPATIAL_DIM_SELECT,
                               DI_SPATIAL_DIMS_PER_NEIGHBOR, DI_SPATIAL_DIMS_PER_SAMPLE, STAGE_PT_SPATIAL)
from ...resampling.mis import pairwise_add_neighbor, pairwise_init, pairwise_normalization
from ...resampling.ris import ris_finalize, ris_init, ris_merge
from ..common.events import stage_events
from ..common.gbuffer import GBuffer
from ..common.reuse_domains import NO_PIXEL, spatial_technique
from ..common.shading import load_shading
from .params import KERNEL_MODULE, PTRParams
from .path_sample import ORIGIN_SPATIAL, PathReservoir, store, with_origin
from .reuse_pair import ShiftTally, make_reuse_pair, tally
from .shift import shift_path

CANONICAL = wp.constant(1000)  # the canonical input's index in the selection (neighbours are 0..k-1)


def make_spatial_kernel(shift=shift_path, drop_failed: bool = False, module=None):
    """The spatial kernel over a shift function; drop_failed builds the mutation that leaves
    neighbours whose shift failed out of the technique set (V, M and the canonical weight)."""
    shift_in, shift_out = make_reuse_pair(shift, module)

    @wp.kernel(module=module or KERNEL_MODULE)
    def spatial_kernel(offset: int, scene: SceneDevice, params: PTRParams, width: int, height: int, gb: GBuffer,
                       reservoirs_in: wp.array(dtype=PathReservoir), reservoirs_out: wp.array(dtype=PathReservoir),
                       shifts: wp.array(dtype=wp.vec4i), events: wp.array(dtype=wp.vec4i)):
        pixel = wp.tid() + offset
        c = reservoirs_in[pixel]
        events[pixel] = wp.vec4i(0)
        shifts[pixel] = wp.vec4i(0)
        sc = load_shading(scene, gb, pixel)
        if sc.valid == 0:
            reservoirs_out[pixel] = c
            return
        p_c = luminance(c.F)
        key = rng_key(params.seed, params.frame, wp.uint32(STAGE_PT_SPATIAL + params.spatial_round), wp.uint32(pixel))
        base = wp.uint32(params.sample) * wp.uint32(DI_SPATIAL_DIMS_PER_SAMPLE)
        s = ris_init()
        mis = pairwise_init(params.spatial_k)
        chosen = c
        tl = ShiftTally()
        for j in range(params.spatial_k):
            dim = base + wp.uint32(j * DI_SPATIAL_DIMS_PER_NEIGHBOR)
            nb = spatial_technique(scene, gb, rng_uniform2(key, dim + wp.uint32(DI_SPATIAL_DIM_OFFSET)), pixel, width,
                                   height, params.spatial_radius, sc)
            if nb.pixel == NO_PIXEL:
                continue
            n = nb.pixel
            sn = nb.sh
            r = reservoirs_in[n]
            # ---- the neighbour's sample here, and this pixel's sample there
            nbr = shift_in(scene, params, r, r.M, c.M, sc)
            tl = tally(tl, r, nbr.t, nbr.tried, 1)
            if wp.static(drop_failed):
                if nbr.t.valid == 0:
                    continue
            own = shift_out(scene, params, c, r.M, sn)
            tl = tally(tl, c, own.t, own.tried, 0)
            mis = pairwise_add_neighbor(mis, nbr.d_i, nbr.d_c, p_c * c.M, own.d_i)
            s = ris_merge(s, mis.m_i, nbr.p_c, nbr.t.J, r.W, r.M, j,
                          rng_uniform(key, dim + wp.uint32(DI_SPATIAL_DIM_SELECT)))
            if s.selected == j:
                chosen = with_origin(nbr.t.r, ORIGIN_SPATIAL)
        # ---- the canonical input last, with its accumulated pairwise weight
        s = ris_merge(s, mis.m_c, p_c, 1.0, c.W, c.M, CANONICAL,
                      rng_uniform(key, base + wp.uint32(DI_SPATIAL_DIM_CANONICAL)))
        if s.selected == CANONICAL:
            chosen = c
        reservoirs_out[pixel] = store(chosen, ris_finalize(s, pairwise_normalization(mis)))
        events[pixel] = stage_events(s, tl.failed, tl.rays)
        shifts[pixel] = tl.counts

    return spatial_kernel


spatial_kernel = make_spatial_kernel()
