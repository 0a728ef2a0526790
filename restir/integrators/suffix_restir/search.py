"""The prefix search structure (ALGORITHMS.md 5.9; docs/suffix_restir.md): one box per pixel
around its resampled prefix end, and the query that finds a fresh prefix end's neighbours, over
one of two structures (the same code on the CPU and CUDA, rebuilt every frame):

- `hashgrid` (default): Warp's hash grid over the box centres (`wp.HashGrid`, cells as wide as
  the largest box's half-size), queried over the cube of that half-size around the point, each
  candidate then tested against its own box;
- `bvh`: Warp's BVH over the boxes (`wp.Bvh`), queried with the point's degenerate box.

Both find the same pixels: those whose box contains the query point x and whose centre lies
within the box's half-diagonal (|c - x|^2 < 3 r^2, 5.9), the M closest first, never one at
distance exactly 0. A pixel's box has centre x_P and half-size r = box_scale x footprint
(box_scale = the radius multiplier x the pixel spread angle: the ray cone of the path; or, with
gather.radius_type=fixed, the multiplier x the scene's smallest extent over the larger image
side, 5.9); pixels without a prefix end get an
empty box at a point far outside the scene. Which pixels are found depends on prefix ends only,
never on suffix samples. (Measured costs of the two: BENCHMARKS.md.)
"""
import warp as wp

from ...device.intersect import surface_at
from ...device.scene_device import SceneDevice
from ...device.streams import SR_MAX_GATHER_SUFFIXES
from ..common.events import ray_events
from ..common.gbuffer import GBuffer
from .params import KERNEL_MODULE
from .prefix import PrefixReservoir, has_prefix

NO_PIXEL = wp.constant(-1)
slots_i = wp.types.vector(length=SR_MAX_GATHER_SUFFIXES, dtype=wp.int32)
slots_f = wp.types.vector(length=SR_MAX_GATHER_SUFFIXES, dtype=float)


SEARCH_HASHGRID = wp.constant(0)
SEARCH_BVH = wp.constant(1)
SEARCHES = {"hashgrid": SEARCH_HASHGRID, "bvh": SEARCH_BVH}


@wp.struct
class SearchStructure:
    kind: int                         # SEARCH_HASHGRID or SEARCH_BVH
    id: wp.uint64                     # the hash grid's or the BVH's id
    radius: float                     # hash grid: the query's half-size (the largest box's half-size)
    centers: wp.array(dtype=wp.vec3)  # the boxes: centre and half-size
    halves: wp.array(dtype=float)


@wp.kernel(module=KERNEL_MODULE)
def boxes_kernel(offset: int, scene: SceneDevice, box_scale: float, box_half: float, far: wp.vec3,
                 prefixes: wp.array(dtype=PrefixReservoir), prefix_gb: GBuffer, centers: wp.array(dtype=wp.vec3),
                 halves: wp.array(dtype=float), lowers: wp.array(dtype=wp.vec3), uppers: wp.array(dtype=wp.vec3),
                 events: wp.array(dtype=wp.vec4i)):
    """Reads: the resampled prefixes and their ends. Writes: the boxes (centre and half-size, and
    for the BVH its lower and upper corners), events."""
    pixel = wp.tid() + offset
    r = prefixes[pixel]
    c = far
    h = float(0.0)
    if has_prefix(r):
        b = prefix_gb.bary[pixel]
        c = surface_at(scene, prefix_gb.tri[pixel], b[0], b[1], 0.0).p
        h = box_scale * r.footprint
        if box_half > 0.0:  # the fixed radius (gather.radius_type=fixed)
            h = box_half
    centers[pixel] = c
    halves[pixel] = h
    if lowers.shape[0] > 0:  # the BVH's corners (empty arrays with the hash grid)
        lowers[pixel] = c - wp.vec3(h)
        uppers[pixel] = c + wp.vec3(h)
    events[pixel] = ray_events(0)


@wp.struct
class Slots:
    """Up to SR_MAX_GATHER_SUFFIXES neighbour pixels (NO_PIXEL: none), closest first."""
    pixel: slots_i
    d2: slots_f
    found: int   # how many the search filled


@wp.func
def empty_slots() -> Slots:
    s = Slots()
    for m in range(SR_MAX_GATHER_SUFFIXES):
        s.pixel[m] = NO_PIXEL
        s.d2[m] = 1.0e30
    return s


@wp.func
def consider(s: Slots, n: int, search: SearchStructure, x: wp.vec3, count: int) -> Slots:
    """s with pixel n inserted in distance order if its box holds x within the half-diagonal."""
    out = s
    c = search.centers[n]
    h = search.halves[n]
    d = c - x
    if wp.max(wp.abs(d[0]), wp.max(wp.abs(d[1]), wp.abs(d[2]))) > h:
        return out
    d2 = wp.length_sq(d)
    if d2 <= 0.0 or d2 >= 3.0 * h * h or d2 >= out.d2[count - 1]:
        return out
    m = count - 1
    while m > 0 and out.d2[m - 1] > d2:
        out.d2[m] = out.d2[m - 1]
        out.pixel[m] = out.pixel[m - 1]
        m -= 1
    out.d2[m] = d2
    out.pixel[m] = n
    return out


@wp.func
def nearest_prefix_ends(search: SearchStructure, x: wp.vec3, count: int) -> Slots:
    """The `count` pixels whose prefix-end box holds x, closest centre first (insertion sort)."""
    s = empty_slots()
    n = int(0)
    if search.kind == SEARCH_BVH:
        query = wp.bvh_query_aabb(search.id, x, x)
        while wp.bvh_query_next(query, n):
            s = consider(s, n, search, x, count)
    else:
        grid_query = wp.hash_grid_query(search.id, x, search.radius)
        while wp.hash_grid_query_next(grid_query, n):
            s = consider(s, n, search, x, count)
    for m in range(count):
        if s.pixel[m] != NO_PIXEL:
            s.found += 1
    return s
