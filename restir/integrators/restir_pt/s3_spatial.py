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
from .params import PTRParams
from .path_sample import ORIGIN_SPATIAL, PathReservoir, holds_path, store, with_origin
from .shift import ShiftResult, shift_counts, shift_path

CANONICAL = wp.constant(1000)  # the canonical input's index in the selection (neighbours are 0..k-1)


def make_spatial_kernel(shift=shift_path, drop_failed: bool = False, module=None):
    """The spatial kernel over a shift function; drop_failed builds the mutation that leaves
    neighbours whose shift failed out of the technique set (V, M and the canonical weight)."""

    @wp.kernel(module=module)
    def spatial_kernel(offset: int, scene: SceneDevice, params: PTRParams, width: int, height: int, gb: GBuffer,
                       reservoirs_in: wp.array(dtype=PathReservoir), reservoirs_out: wp.array(dtype=PathReservoir),
                       shifts: wp.array(dtype=wp.vec4i), events: wp.array(dtype=wp.vec4i)):
        pixel = wp.tid() + offset
        c = reservoirs_in[pixel]
        events[pixel] = wp.vec4i(0)
        shifts[pixel] = wp.vec4i(0)
        counts = wp.vec4i(0)
        sc = load_shading(scene, gb, pixel)
        if sc.valid == 0:
            reservoirs_out[pixel] = c
            return
        p_c = luminance(c.F)
        has_c = holds_path(c) and c.W > 0.0
        key = rng_key(params.seed, params.frame, wp.uint32(STAGE_PT_SPATIAL + params.spatial_round), wp.uint32(pixel))
        base = wp.uint32(params.sample) * wp.uint32(DI_SPATIAL_DIMS_PER_SAMPLE)
        s = ris_init()
        mis = pairwise_init(params.spatial_k)
        chosen = c
        failed = int(0)
        rays = int(0)
        for j in range(params.spatial_k):
            dim = base + wp.uint32(j * DI_SPATIAL_DIMS_PER_NEIGHBOR)
            nb = spatial_technique(scene, gb, rng_uniform2(key, dim + wp.uint32(DI_SPATIAL_DIM_OFFSET)), pixel, width,
                                   height, params.spatial_radius, sc)
            if nb.pixel == NO_PIXEL:
                continue
            n = nb.pixel
            sn = nb.sh
            r = reservoirs_in[n]
            # ---- the neighbour's sample here
            fwd = ShiftResult()
            if holds_path(r) and r.W > 0.0:
                fwd = shift(scene, params, r, sc)
                rays += fwd.rays
                failed += 1 - fwd.valid
                counts += shift_counts(r, fwd)
            if wp.static(drop_failed):
                if fwd.valid == 0:
                    continue
            # The neighbour's weight compares p_hat_n(x_n) / J M_n with p_hat_c(y) M_c; both are
            # passed times J (the weight is a ratio), so that a tiny J cannot overflow it to inf/inf.
            p_c_at_y = float(0.0)
            d_n_at_y = float(0.0)
            if fwd.valid != 0:
                p_c_at_y = luminance(fwd.r.F)
                d_n_at_y = luminance(r.F) * r.M
            # ---- this pixel's sample there
            d_n_at_xc = float(0.0)
            if has_c:
                back = shift(scene, params, c, sn)
                rays += back.rays
                counts += shift_counts(c, back)
                if back.valid != 0:
                    d_n_at_xc = luminance(back.r.F) * back.J * r.M
            mis = pairwise_add_neighbor(mis, d_n_at_y, p_c_at_y * c.M * fwd.J, p_c * c.M, d_n_at_xc)
            s = ris_merge(s, mis.m_i, p_c_at_y, fwd.J, r.W, r.M, j,
                          rng_uniform(key, dim + wp.uint32(DI_SPATIAL_DIM_SELECT)))
            if s.selected == j:
                chosen = with_origin(fwd.r, ORIGIN_SPATIAL)
        # ---- the canonical input last, with its accumulated pairwise weight
        s = ris_merge(s, mis.m_c, p_c, 1.0, c.W, c.M, CANONICAL,
                      rng_uniform(key, base + wp.uint32(DI_SPATIAL_DIM_CANONICAL)))
        if s.selected == CANONICAL:
            chosen = c
        reservoirs_out[pixel] = store(chosen, ris_finalize(s, pairwise_normalization(mis)))
        events[pixel] = stage_events(s, failed, rays)
        shifts[pixel] = counts

    return spatial_kernel


spatial_kernel = make_spatial_kernel()
