"""Stage 4, spatial reuse: pairwise MIS over the pixel and k neighbours (docs/theory/restir_di.md#spatial-reuse).

Neighbours: k pixels drawn uniformly in a disk of `spatial_radius` pixels around the pixel,
kept when on screen, with a primary hit, not the pixel itself and geometrically similar: a
choice that depends on the G-buffer only, never on reservoir contents (empty or zero
neighbours stay in the technique set with weight 0). Light samples move between primary hits
unchanged (area / solid-angle measure: J = 1); both own-domain targets are re-evaluated from the
G-buffer. Targets and MIS densities are either unshadowed (visibility enters at shading) or
visibility-aware (two shadow rays per neighbour: its sample here, this pixel's sample there).
Reads: scene, G-buffer, reservoirs_in. Writes: reservoirs_out (a different buffer: ping-pong),
events.
"""
import warp as wp

from ...device.rng import rng_key, rng_uniform, rng_uniform2
from ...device.scene_device import SceneDevice
from ...device.streams import (DI_SPATIAL_DIM_CANONICAL, DI_SPATIAL_DIM_OFFSET, DI_SPATIAL_DIM_SELECT,
                               DI_SPATIAL_DIMS_PER_NEIGHBOR, DI_SPATIAL_DIMS_PER_SAMPLE, STAGE_DI_SPATIAL)
from ...resampling.mis import pairwise_add_neighbor, pairwise_init, pairwise_normalization
from ...resampling.ris import ris_finalize, ris_init, ris_merge
from ..common.events import EventCounts, packed_events, stage_events
from ..common.gbuffer import GBuffer
from ..common.reuse_domains import NO_PIXEL, spatial_technique
from ..common.shading import load_shading
from .params import DIParams
from .reservoir import DIReservoir, own_target, store, target

CANONICAL = wp.constant(1000)  # the canonical input's index in the selection (neighbours are 0..k-1)


def make_spatial_kernel(skip_zero_canonical: bool = False, drop_empty_neighbors: bool = False):
    """The spatial kernel; the arguments build fault-injected variants for the mutation tests
    (docs/validation.md#power-checks-the-mutation-table: A1, and A3, neighbours holding no sample
    excluded from k). Those variants
    are compiled into modules of their own; the shipped kernel is built with neither."""
    mutated = skip_zero_canonical or drop_empty_neighbors

    @wp.kernel(module="unique" if mutated else None)
    def spatial_kernel(offset: int, scene: SceneDevice, params: DIParams, width: int, height: int, gb: GBuffer,
                       reservoirs_in: wp.array(dtype=DIReservoir), reservoirs_out: wp.array(dtype=DIReservoir),
                       events: wp.array(dtype=EventCounts)):
        pixel = wp.tid() + offset
        c = reservoirs_in[pixel]
        events[pixel] = packed_events(wp.vec4i(0))
        sc = load_shading(scene, gb, pixel)
        if sc.valid == 0:
            reservoirs_out[pixel] = c
            return
        vis = params.visibility
        p_c = own_target(scene, sc, c, vis)
        if wp.static(skip_zero_canonical):
            if p_c * c.W == 0.0:
                reservoirs_out[pixel] = c
                return
        key = rng_key(params.seed, params.frame, wp.uint32(STAGE_DI_SPATIAL + params.spatial_round), wp.uint32(pixel))
        base = wp.uint32(params.sample) * wp.uint32(DI_SPATIAL_DIMS_PER_SAMPLE)
        s = ris_init()
        mis = pairwise_init(params.spatial_k)
        chosen = c
        failed = int(0)
        rays = float(0.0)
        for j in range(params.spatial_k):
            dim = base + wp.uint32(j * DI_SPATIAL_DIMS_PER_NEIGHBOR)
            # ---- neighbour choice: geometry and screen position only
            nb = spatial_technique(scene, gb, rng_uniform2(key, dim + wp.uint32(DI_SPATIAL_DIM_OFFSET)), pixel, width,
                                   height, params.spatial_radius, sc)
            if nb.pixel == NO_PIXEL:
                continue
            n = nb.pixel
            sn = nb.sh
            r = reservoirs_in[n]
            if wp.static(drop_empty_neighbors):
                if r.W <= 0.0:
                    continue
            # ---- the neighbour's sample here, and this pixel's sample there (both J = 1)
            t_c = target(scene, sc, r, vis)
            p_c_at_n = t_c[0]
            t_n = target(scene, sn, c, vis)
            mis = pairwise_add_neighbor(mis, own_target(scene, sn, r, vis) * r.M, p_c_at_n * c.M, p_c * c.M,
                                        t_n[0] * r.M)
            s = ris_merge(s, mis.m_i, p_c_at_n, 1.0, r.W, r.M, j,
                          rng_uniform(key, dim + wp.uint32(DI_SPATIAL_DIM_SELECT)))
            if s.selected == j:
                chosen = r
            failed += wp.where(r.W > 0.0 and p_c_at_n <= 0.0, 1, 0)
            rays += t_c[1] + t_n[1]
        # ---- the canonical input last, with its accumulated pairwise weight
        s = ris_merge(s, mis.m_c, p_c, 1.0, c.W, c.M, CANONICAL,
                      rng_uniform(key, base + wp.uint32(DI_SPATIAL_DIM_CANONICAL)))
        if s.selected == CANONICAL:
            chosen = c
        reservoirs_out[pixel] = store(chosen, ris_finalize(s, pairwise_normalization(mis)))
        events[pixel] = packed_events(stage_events(s, failed, int(rays)))

    return spatial_kernel


spatial_kernel = make_spatial_kernel()
