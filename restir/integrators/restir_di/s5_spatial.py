"""Stage 4, spatial reuse: pairwise MIS over the pixel and k neighbours (ALGORITHMS.md 4.3).

Neighbours: k pixels drawn uniformly in a disk of `spatial_radius` pixels around the pixel,
kept when on screen, with a primary hit, not the pixel itself and geometrically similar: a
choice that depends on the G-buffer only, never on reservoir contents (empty or zero
neighbours stay in the technique set with weight 0). Light samples move between primary hits
unchanged (area / solid-angle measure: J = 1); both own-domain targets are re-evaluated from the
G-buffers. Targets and MIS densities are either unshadowed (visibility enters at shading) or
visibility-aware (two shadow rays per neighbour: its sample here, this pixel's sample there).
Reads: scene, G-buffer, reservoirs_in. Writes: reservoirs_out (a different buffer: ping-pong),
events.
"""
import warp as wp

from ...device.rng import rng_key, rng_uniform, rng_uniform2
from ...device.sampling import square_to_uniform_disk_concentric
from ...device.scene_device import SceneDevice
from ...device.types import STAGE_DI_SPATIAL
from ...resampling.mis import pairwise_canonical_term, pairwise_neighbor_weight
from ...resampling.ris import ris_contribution_weight, ris_init, ris_stream
from .events import stage_events
from .gbuffer import load_shading, similar_surfaces
from .params import DIParams
from .reservoir import DIReservoir, own_target, target


@wp.kernel
def spatial_kernel(offset: int, scene: SceneDevice, params: DIParams, width: int, height: int,
                   gb_tri: wp.array(dtype=wp.int32), gb_bary: wp.array(dtype=wp.vec2), gb_t: wp.array(dtype=float),
                   gb_dir: wp.array(dtype=wp.vec3), reservoirs_in: wp.array(dtype=DIReservoir),
                   reservoirs_out: wp.array(dtype=DIReservoir), events: wp.array(dtype=wp.vec4i)):
    pixel = wp.tid() + offset
    c = reservoirs_in[pixel]
    events[pixel] = wp.vec4i(0)
    sc = load_shading(scene, gb_tri, gb_bary, gb_t, gb_dir, pixel)
    if sc.valid == 0:
        reservoirs_out[pixel] = c
        return
    vis = params.visibility
    p_c = own_target(scene, sc, c, vis)
    if params.mut_skip_zero_canonical != 0 and p_c * c.W == 0.0:
        reservoirs_out[pixel] = c
        return
    key = rng_key(params.seed, params.frame, wp.uint32(STAGE_DI_SPATIAL + params.spatial_round), wp.uint32(pixel))
    base = wp.uint32(params.sample * 256)
    px = pixel % width
    py = pixel // width
    s = ris_init()
    out = c
    m_c = float(1.0)
    V = int(0)
    failed = int(0)
    rays = float(0.0)
    for j in range(params.spatial_k):
        # ---- neighbour choice: geometry and screen position only
        o = square_to_uniform_disk_concentric(rng_uniform2(key, base + wp.uint32(4 * j))) * params.spatial_radius
        nx = px + int(wp.round(o[0]))
        ny = py + int(wp.round(o[1]))
        if nx < 0 or ny < 0 or nx >= width or ny >= height or (nx == px and ny == py):
            continue
        n = ny * width + nx
        sn = load_shading(scene, gb_tri, gb_bary, gb_t, gb_dir, n)
        if sn.valid == 0 or not similar_surfaces(sc, sn):
            continue
        r = reservoirs_in[n]
        if params.mut_drop_empty != 0 and r.W <= 0.0:
            continue
        V += 1
        # ---- the neighbour's sample, resampled in this pixel's domain
        t_c = target(scene, sc, r, vis)
        p_c_at_n = t_c[0]
        p_n_at_n = own_target(scene, sn, r, vis)
        failed += wp.where(r.W > 0.0 and p_c_at_n <= 0.0, 1, 0)
        m_n = pairwise_neighbor_weight(p_n_at_n * r.M, p_c_at_n * c.M, params.spatial_k)
        s = ris_stream(s, m_n * p_c_at_n * r.W, p_c_at_n, r.M, j, rng_uniform(key, base + wp.uint32(4 * j + 2)))
        if s.selected == j:
            out = r
        # ---- this pixel's share against that neighbour
        t_n = target(scene, sn, c, vis)
        m_c += pairwise_canonical_term(p_c * c.M, t_n[0] * r.M, params.spatial_k)
        rays += t_c[1] + t_n[1]
    s = ris_stream(s, m_c * p_c * c.W, p_c, c.M, 1000, rng_uniform(key, base + wp.uint32(255)))
    if s.selected == 1000:
        out = c
    out.W = ris_contribution_weight(s, float(V + 1))
    out.M = s.M
    if s.selected < 0:  # nothing could be selected: an empty reservoir that still carries M
        out.light_tri = -2
    reservoirs_out[pixel] = out
    events[pixel] = stage_events(s, failed, int(rays))
