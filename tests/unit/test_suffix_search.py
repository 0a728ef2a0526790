"""The prefix search structure (s2_search.py): the sorted grid, the hash grid and the BVH find the same
neighbours, and those are exactly the ones a brute-force scan over every pixel's box finds (the box holds
the query point, the centre lies within its half-diagonal, closest first, none at distance 0),
on the resampled prefix ends of a real frame, queried at fresh prefix ends. (Ties: pixels that
adopted the same previous prefix end share a centre, and which of them the BVH lists first
depends on its traversal order.)"""
import numpy as np
import warp as wp

import restir
from restir.api import make_integrator
from restir.device.rng import hash_combine, rng_key
from restir.device.scene_device import SceneDevice
from restir.device.streams import SR_MAX_GATHER_SUFFIXES
from restir.integrators.common.gbuffer import GBuffer
from restir.integrators.common.shading import load_shading
from restir.integrators.suffix_restir.params import SRParams
from restir.integrators.suffix_restir.prefix import trace_prefix
from restir.integrators.suffix_restir.s2_search import SearchStructure, nearest_prefix_ends

M = 4


@wp.kernel
def query_kernel(scene: SceneDevice, params: SRParams, gb: GBuffer, search: SearchStructure,
                 points: wp.array(dtype=wp.vec3), found: wp.array2d(dtype=int)):
    pixel = wp.tid()
    for m in range(M):
        found[pixel, m] = -1
    points[pixel] = wp.vec3(1.0e30)
    sc = load_shading(scene, gb, pixel)
    if sc.valid == 0:
        return
    pf = trace_prefix(scene, params, sc, hash_combine(rng_key(wp.uint32(9), wp.uint32(1), wp.uint32(2),
                                                              wp.uint32(pixel)), wp.uint32(0)), False)
    if pf.valid == 0:
        return
    points[pixel] = pf.hit.p
    s = nearest_prefix_ends(search, pf.hit.p, M)
    for m in range(M):
        found[pixel, m] = s.pixel[m]


def neighbours(kind):
    scene = restir.load_scene("builtin:cornell-box-glossy", width=64, height=64)
    integ = make_integrator(scene, restir.RenderConfig(method="suffix-restir", spp=1, max_depth=5, seed=2,
                                                       settings={"gather.search": kind}))
    integ.render_frame(0)
    integ.render_frame(1)
    n = integ.num_pixels
    found = wp.zeros((n, M), dtype=int, device=integ.device)
    points = wp.zeros(n, dtype=wp.vec3, device=integ.device)
    wp.launch(query_kernel, dim=n, device=integ.device,
              inputs=[integ.dscene.scene, integ.params(1, 0), integ.gbuffers.previous, integ.search, points, found])
    return found.numpy(), points.numpy(), integ.search.centers.numpy(), integ.search.halves.numpy()


def brute_force(points, centers, halves):
    out = np.full((len(points), M), -1)
    for i, x in enumerate(points):
        if x[0] > 1e29:
            continue
        d = centers - x
        d2 = (d.astype(np.float64) ** 2).sum(1)
        ok = (np.abs(d).max(1) <= halves) & (d2 > 0) & (d2 < 3.0 * halves.astype(np.float64) ** 2)
        idx = np.nonzero(ok)[0]
        idx = idx[np.argsort(d2[idx], kind="stable")][:M]
        out[i, :len(idx)] = idx
    return out


def test_every_structure_finds_the_brute_force_neighbours():
    assert M <= SR_MAX_GATHER_SUFFIXES
    grid, points, centers, halves = neighbours("hashgrid")
    bvh, points_b, _, _ = neighbours("bvh")
    sorted_grid, points_s, _, _ = neighbours("grid")
    np.testing.assert_array_equal(points, points_b)  # the same frames, the same fresh prefix ends
    np.testing.assert_array_equal(points, points_s)
    expect = brute_force(points, centers, halves)
    found = (grid >= 0).sum()
    print(f"{(points[:, 0] < 1e29).sum()} queries, {found} neighbours found, {(grid >= 0).any(1).mean():.1%} with one")
    assert found > 1000
    # the same neighbours, up to which of two pixels at exactly the same distance fills the last
    # slot (pixels that adopted the same previous prefix end share a centre): compare distances
    def dist(f):
        q = np.where(points[:, None, :] < 1e29, points[:, None, :], 0.0).astype(np.float64)
        d2 = np.where(f >= 0, ((centers[np.maximum(f, 0)] - q) ** 2).sum(-1), -1.0)
        return np.sort(d2, 1)

    assert np.array_equal(dist(grid), dist(expect))
    assert np.array_equal(dist(bvh), dist(expect))
    assert np.array_equal(dist(sorted_grid), dist(expect))
    for row in sorted_grid:  # no pixel twice (a slot shared by two cells is read once)
        found = row[row >= 0]
        assert len(np.unique(found)) == len(found)
