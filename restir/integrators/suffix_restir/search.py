"""The prefix search structure (ALGORITHMS.md 5.9; docs/suffix_restir.md): one box per pixel
around its resampled prefix end, a BVH over the boxes (Warp's `wp.Bvh`, the same code on the CPU
and CUDA, rebuilt every frame), and the query that finds a fresh prefix end's neighbours.

A pixel's box has centre x_P and half-size r = box_scale x footprint (box_scale = the radius
multiplier x the pixel spread angle); pixels without a prefix end get an empty box at a point far
outside the scene. A query point x finds the pixels whose box contains it and whose centre lies
within the box's half-diagonal (|c - x|^2 < 3 r^2), the M closest first, never one at distance
exactly 0. Which pixels are found depends on prefix ends only, never on suffix samples.
"""
import warp as wp

from ...device.intersect import surface_at
from ...device.scene_device import SceneDevice
from ...device.streams import SR_MAX_GATHER_SUFFIXES
from ..common.events import ray_events
from ..common.gbuffer import GBuffer
from .prefix import PrefixReservoir, has_prefix

NO_PIXEL = wp.constant(-1)
slots_i = wp.types.vector(length=SR_MAX_GATHER_SUFFIXES, dtype=wp.int32)
slots_f = wp.types.vector(length=SR_MAX_GATHER_SUFFIXES, dtype=float)


@wp.kernel
def boxes_kernel(offset: int, scene: SceneDevice, box_scale: float, far: wp.vec3,
                 prefixes: wp.array(dtype=PrefixReservoir), prefix_gb: GBuffer, lowers: wp.array(dtype=wp.vec3),
                 uppers: wp.array(dtype=wp.vec3), events: wp.array(dtype=wp.vec4i)):
    """Reads: the resampled prefixes and their ends. Writes: the boxes, events."""
    pixel = wp.tid() + offset
    r = prefixes[pixel]
    lo = far
    hi = far
    if has_prefix(r):
        b = prefix_gb.bary[pixel]
        c = surface_at(scene, prefix_gb.tri[pixel], b[0], b[1], 0.0).p
        h = box_scale * r.footprint
        lo = c - wp.vec3(h)
        hi = c + wp.vec3(h)
    lowers[pixel] = lo
    uppers[pixel] = hi
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
def nearest_prefix_ends(bvh: wp.uint64, lowers: wp.array(dtype=wp.vec3), uppers: wp.array(dtype=wp.vec3),
                        x: wp.vec3, count: int) -> Slots:
    """The `count` pixels whose prefix-end box holds x, closest centre first (insertion sort)."""
    s = empty_slots()
    query = wp.bvh_query_aabb(bvh, x, x)
    n = int(0)
    while wp.bvh_query_next(query, n):
        lo = lowers[n]
        hi = uppers[n]
        c = 0.5 * (lo + hi)
        h = 0.5 * (hi[0] - lo[0])
        d2 = wp.length_sq(c - x)
        if d2 <= 0.0 or d2 >= 3.0 * h * h:
            continue
        if d2 >= s.d2[count - 1]:
            continue
        m = count - 1
        while m > 0 and s.d2[m - 1] > d2:
            s.d2[m] = s.d2[m - 1]
            s.pixel[m] = s.pixel[m - 1]
            m -= 1
        s.d2[m] = d2
        s.pixel[m] = n
    for m in range(count):
        if s.pixel[m] != NO_PIXEL:
            s.found += 1
    return s
