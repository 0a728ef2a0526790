"""The prefix search structure (docs/theory/suffix_restir.md#the-prefix-search;
docs/guide/suffix_restir.md): one box per pixel around its resampled prefix end, and the query that
finds a fresh prefix end's neighbours, over one of three structures (the same code on the CPU and
CUDA, rebuilt every frame):

- `grid` (default): a hashed uniform grid over the box centres, sorted by cell, with the boxes
  copied into that order, so a query reads each cell's candidates as one contiguous run. Cells
  are twice as wide as the largest half-size r, so the cube [x - r, x + r]^3 that holds every
  candidate centre overlaps at most 2 x 2 x 2 cells: 8 table lookups per query, then contiguous
  reads. (Warp's hash grid below returns candidates as pixel indices, each a random read of its
  box: at 800x800 the query became memory-bound, docs/changelog.md#suffix-restir-gathersearchgrid.)
- `hashgrid`: Warp's hash grid over the box centres (`wp.HashGrid`, cells as wide as the
  largest box's half-size), queried over the cube of that half-size around the point, each
  candidate then tested against its own box;
- `bvh`: Warp's BVH over the boxes (`wp.Bvh`), queried with the point's degenerate box.

Both find the same pixels: those whose box contains the query point x and whose centre lies
within the box's half-diagonal (|c - x|^2 < 3 r^2), the M closest first, never one at
distance exactly 0. A pixel's box has centre x_P and half-size r = box_scale x footprint
(box_scale = the radius multiplier x the pixel spread angle: the ray cone of the path; or, with
gather.radius_type=fixed, the multiplier x the scene's smallest extent over the larger image
side); pixels without a prefix end get an
empty box at a point far outside the scene. Which pixels are found depends on prefix ends only,
never on suffix samples. (Measured costs: docs/changelog.md#suffix-restir-gathersearchgrid.)
"""
import warp as wp

from ...device.intersect import surface_at
from ...device.scene_device import SceneDevice
from ...device.streams import SR_MAX_GATHER_SUFFIXES
from ..common.events import EventCounts, packed_events, ray_events
from ..common.gbuffer import GBuffer
from .params import KERNEL_MODULE
from .prefix import PrefixReservoir, has_prefix

NO_PIXEL = wp.constant(-1)
slots_i = wp.types.vector(length=SR_MAX_GATHER_SUFFIXES, dtype=wp.int32)
slots_f = wp.types.vector(length=SR_MAX_GATHER_SUFFIXES, dtype=float)


SEARCH_HASHGRID = wp.constant(0)
SEARCH_BVH = wp.constant(1)
SEARCH_GRID = wp.constant(2)
SEARCHES = {"grid": SEARCH_GRID, "hashgrid": SEARCH_HASHGRID, "bvh": SEARCH_BVH}


@wp.struct
class SearchStructure:
    kind: int                         # SEARCH_GRID, SEARCH_HASHGRID or SEARCH_BVH
    id: wp.uint64                     # the hash grid's or the BVH's id
    radius: float                     # grids: the query's half-size (the largest box's half-size)
    centers: wp.array(dtype=wp.vec3)  # the boxes by pixel: centre (not kept for the sorted grid) and half-size
    halves: wp.array(dtype=float)
    # the sorted grid (empty arrays for the others): 1 / cell width, the hash table's mask, the
    # sort's slots and pixels, the entries in slot order, each slot's range of entries
    inv_cell: float
    mask: int
    keys: wp.array(dtype=wp.int32)
    ids: wp.array(dtype=wp.int32)
    entries: wp.array(dtype=wp.vec4)  # the boxes in slot order, (centre, half-size): one 16-byte read a candidate
    ranges: wp.array(dtype=wp.vec2i)


@wp.func
def box_center(scene: SceneDevice, prefix_gb: GBuffer, pixel: int) -> wp.vec3:
    """The centre of a pixel's box: its resampled prefix end."""
    b = prefix_gb.bary[pixel]
    return surface_at(scene, prefix_gb.tri[pixel], b[0], b[1], 0.0).p


@wp.kernel(module=KERNEL_MODULE)
def boxes_kernel(offset: int, scene: SceneDevice, box_scale: float, box_half: float, far: wp.vec3,
                 prefixes: wp.array(dtype=PrefixReservoir), prefix_gb: GBuffer, centers: wp.array(dtype=wp.vec3),
                 halves: wp.array(dtype=float), lowers: wp.array(dtype=wp.vec3), uppers: wp.array(dtype=wp.vec3),
                 events: wp.array(dtype=EventCounts)):
    """Reads: the resampled prefixes and their ends. Writes: the boxes (centre and half-size, and
    for the BVH its lower and upper corners), events."""
    pixel = wp.tid() + offset
    r = prefixes[pixel]
    c = far
    h = float(0.0)
    if has_prefix(r):
        c = box_center(scene, prefix_gb, pixel)
        h = box_scale * r.footprint
        if box_half > 0.0:  # the fixed radius (gather.radius_type=fixed)
            h = box_half
    if centers.shape[0] > 0:  # (the sorted grid keeps no centres by pixel: box_center again)
        centers[pixel] = c
    halves[pixel] = h
    if lowers.shape[0] > 0:  # the BVH's corners (empty arrays with the hash grid)
        lowers[pixel] = c - wp.vec3(h)
        uppers[pixel] = c + wp.vec3(h)
    events[pixel] = packed_events(ray_events(0))


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
    return consider_box(s, n, search.centers[n], search.halves[n], x, count)


@wp.func
def outside_box(c: wp.vec3, h: float, x: wp.vec3) -> bool:
    """x lies outside the box of centre c and half-size h."""
    d = c - x
    return wp.max(wp.abs(d[0]), wp.max(wp.abs(d[1]), wp.abs(d[2]))) > h


@wp.func
def consider_box(s: Slots, n: int, c: wp.vec3, h: float, x: wp.vec3, count: int) -> Slots:
    """s with pixel n (box: centre c, half-size h) inserted in distance order if its box holds x
    within the half-diagonal."""
    out = s
    if outside_box(c, h, x):
        return out
    d = c - x
    d2 = wp.length_sq(d)
    if d2 <= 0.0 or d2 >= 3.0 * h * h or d2 >= out.d2[count - 1]:
        return out
    for k in range(count):  # two cells of one table slot visit its run twice
        if out.pixel[k] == n:
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
    if search.kind == SEARCH_GRID:
        s = grid_candidates(s, search, x, count)
    elif search.kind == SEARCH_BVH:
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


# ---- the sorted grid

@wp.func
def grid_cell(search: SearchStructure, p: wp.vec3) -> wp.vec3i:
    return wp.vec3i(int(wp.floor(p[0] * search.inv_cell)), int(wp.floor(p[1] * search.inv_cell)),
                    int(wp.floor(p[2] * search.inv_cell)))


@wp.func
def grid_slot(search: SearchStructure, c: wp.vec3i) -> int:
    """The hash table slot of cell c (cells that share a slot share its run: the box test sorts
    them out)."""
    h = (wp.uint32(c[0]) * wp.uint32(73856093)) ^ (wp.uint32(c[1]) * wp.uint32(19349663)) ^ (
        wp.uint32(c[2]) * wp.uint32(83492791))
    return int(h & wp.uint32(search.mask))


@wp.func
def grid_candidates(s: Slots, search: SearchStructure, x: wp.vec3, count: int) -> Slots:
    """s with every box of the cells overlapping [x - r, x + r]^3 considered (at most 2 x 2 x 2:
    cells are 2.02 r wide). Two cells that share a table slot read its run twice; consider_box
    keeps a pixel once. (Slots deduplicated first, or cells half or a third as wide with up to
    27 lookups, or runs sorted by x with a binary search: all slower,
    docs/changelog.md#speed-the-prefix-searchs-candidate-loop.)"""
    out = s
    lo = grid_cell(search, x - wp.vec3(search.radius))
    hi = grid_cell(search, x + wp.vec3(search.radius))
    for cz in range(lo[2], hi[2] + 1):  # (one loop over a flat cell index, with / and %: 10% slower)
        for cy in range(lo[1], hi[1] + 1):
            for cx in range(lo[0], hi[0] + 1):
                run = search.ranges[grid_slot(search, wp.vec3i(cx, cy, cz))]
                i = next_holding(search, run[0], run[1], x)
                while i < run[1]:
                    e = search.entries[i]
                    out = consider_box(out, search.ids[i], wp.vec3(e[0], e[1], e[2]), e[3], x, count)
                    i = next_holding(search, i + 1, run[1], x)
    return out


@wp.func
def next_holding(search: SearchStructure, start: int, end: int, x: wp.vec3) -> int:
    """The first entry in [start, end) whose box holds x (end if none). Its own loop: most
    candidates fail the box test (45 a query, 7 boxes holding x, on the Cornell box), and a loop
    that carried the slots (68 bytes) copied them at every candidate."""
    i = start
    while i < end:
        e = search.entries[i]
        if not outside_box(wp.vec3(e[0], e[1], e[2]), e[3], x):
            return i
        i += 1
    return end


@wp.kernel(module=KERNEL_MODULE)
def grid_keys_kernel(offset: int, scene: SceneDevice, prefix_gb: GBuffer, search: SearchStructure,
                     keys: wp.array(dtype=wp.int32), ids: wp.array(dtype=wp.int32), events: wp.array(dtype=EventCounts)):
    """Reads: the boxes' half-sizes, the prefix ends. Writes: each pixel's table slot (boxes without a prefix end: the slot past
    the table, sorted last and never visited) and its pixel index, the sort's input."""
    pixel = wp.tid() + offset
    slot = search.mask + 1
    if search.halves[pixel] > 0.0:
        slot = grid_slot(search, grid_cell(search, box_center(scene, prefix_gb, pixel)))
    keys[pixel] = slot
    ids[pixel] = pixel
    events[pixel] = packed_events(ray_events(0))


@wp.kernel(module=KERNEL_MODULE)
def grid_order_kernel(offset: int, scene: SceneDevice, prefix_gb: GBuffer, search: SearchStructure, count: int,
                      entries: wp.array(dtype=wp.vec4), ranges: wp.array(dtype=wp.vec2i),
                      events: wp.array(dtype=EventCounts)):
    """Reads: the sorted slots and pixels, the boxes' half-sizes, the prefix ends. Writes: the entries in sorted order,
    and where a slot's run begins or ends, that bound of its range (the table was zeroed before:
    empty slots keep the empty range)."""
    i = wp.tid() + offset
    n = search.ids[i]
    h = search.halves[n]
    c = wp.vec3(0.0)
    if h > 0.0:
        c = box_center(scene, prefix_gb, n)
    entries[i] = wp.vec4(c[0], c[1], c[2], h)
    slot = search.keys[i]
    if slot <= search.mask:
        if i == 0 or search.keys[i - 1] != slot:
            ranges[slot][0] = i
        if i == count - 1 or search.keys[i + 1] != slot:
            ranges[slot][1] = i + 1
    events[i] = packed_events(ray_events(0))
