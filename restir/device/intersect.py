"""Ray queries: closest hit and visibility, with Mitsuba's self-intersection offsets.

All tracing goes through `trace_closest` and `unblocked`: Embree on the CPU, Warp's BVH on
CUDA (device/native_trace.py), so every stage stays single-source.
"""
import warp as wp

from .native_trace import native_closest_hit, native_occluded
from .scene_device import SceneDevice
from .types import NO_TRIANGLE

# Mitsuba: RayEpsilon = 1500 * 2^-24, ShadowEpsilon = 10 * RayEpsilon.
RAY_EPSILON = wp.constant(8.940696716308594e-05)
SHADOW_EPSILON = wp.constant(8.940696716308594e-04)
T_MAX = wp.constant(1.0e30)


@wp.struct
class SurfaceHit:
    valid: int
    t: float
    p: wp.vec3
    ng: wp.vec3    # unit geometric normal (triangle winding)
    ns: wp.vec3    # unit shading normal
    uv: wp.vec2
    tri: int
    bary: wp.vec2  # Warp barycentrics (weights of corners 0 and 1): (tri, bary, t) rebuild the hit


@wp.func
def offset_origin(p: wp.vec3, ng: wp.vec3, d: wp.vec3) -> wp.vec3:
    """Move p off the surface, to the side of ng that d points to."""
    mag = (1.0 + wp.max(wp.max(wp.abs(p[0]), wp.abs(p[1])), wp.abs(p[2]))) * RAY_EPSILON
    return p + ng * wp.where(wp.dot(ng, d) >= 0.0, mag, -mag)


@wp.func
def surface_at(scene: SceneDevice, tri: int, bu: float, bv: float, t: float) -> SurfaceHit:
    """Reconstruct a hit from a triangle and Warp's barycentrics (p = u*p0 + v*p1 + w*p2)."""
    bw = 1.0 - bu - bv
    i0 = 3 * tri
    p0 = scene.positions[i0]
    p1 = scene.positions[i0 + 1]
    p2 = scene.positions[i0 + 2]
    h = SurfaceHit()
    h.valid = 1
    h.t = t
    h.tri = tri
    h.bary = wp.vec2(bu, bv)
    h.p = p0 * bu + p1 * bv + p2 * bw
    h.ng = wp.normalize(wp.cross(p1 - p0, p2 - p0))
    h.ns = h.ng
    if scene.tri_smooth[tri] != 0:
        n = scene.normals[i0] * bu + scene.normals[i0 + 1] * bv + scene.normals[i0 + 2] * bw
        ln = wp.length(n)
        if ln > 0.0:
            h.ns = n / ln
    h.uv = scene.uvs[i0] * bu + scene.uvs[i0 + 1] * bv + scene.uvs[i0 + 2] * bw
    return h


@wp.func
def trace_closest(scene: SceneDevice, o: wp.vec3, d: wp.vec3, t_max: float) -> SurfaceHit:
    q = native_closest_hit(scene.mesh, scene.embree_scene, scene.embree_intersect, o, d, t_max)
    if q[0] < 0.0:
        h = SurfaceHit()
        h.valid = 0
        h.t = T_MAX
        h.tri = NO_TRIANGLE
        return h
    return surface_at(scene, int(q[3]), q[1], q[2], q[0])


@wp.func
def unblocked(mesh: wp.uint64, embree_scene: wp.uint64, embree_occluded: wp.uint64, o: wp.vec3, d: wp.vec3,
              dist: float) -> bool:
    """True if nothing blocks the unit direction d from o over (0, dist); stops short of the end."""
    return not native_occluded(mesh, embree_scene, embree_occluded, o, d, dist * (1.0 - SHADOW_EPSILON))


@wp.func
def is_visible(scene: SceneDevice, o: wp.vec3, d: wp.vec3, dist: float) -> bool:
    return unblocked(scene.mesh, scene.embree_scene, scene.embree_occluded, o, d, dist)


@wp.func(inline=False)
def segment_unblocked(mesh: wp.uint64, embree_scene: wp.uint64, embree_occluded: wp.uint64, p: wp.vec3, ng: wp.vec3,
                      wi: wp.vec3, light_p: wp.vec3, light_n: wp.vec3, is_env: int) -> bool:
    """visible_to_light's work, out of line on the three handles it reads. Warp passes structs by
    value: taking the whole SceneDevice (1152 B), this function, which the reuse kernels' inliner
    keeps out of line, copied it at every shadow ray
    (docs/changelog.md#speed-functions-that-copied-the-scene-inlined)."""
    origin = offset_origin(p, ng, wi)
    if is_env != 0:
        return unblocked(mesh, embree_scene, embree_occluded, origin, wi, T_MAX)
    target = offset_origin(light_p, light_n, -wi)
    seg = target - origin
    dist = wp.length(seg)
    return dist > 0.0 and unblocked(mesh, embree_scene, embree_occluded, origin, seg / dist, dist)


@wp.func(inline=True)
def visible_to_light(scene: SceneDevice, p: wp.vec3, ng: wp.vec3, wi: wp.vec3, light_p: wp.vec3, light_n: wp.vec3,
                     is_env: int) -> bool:
    """The one shadow ray of every light connection: from surface point p (geometric normal ng)
    along unit direction wi to the light point light_p (normal light_n), or to the environment.
    Both ends are offset off their surfaces, so neither surface occludes its own connection."""
    return segment_unblocked(scene.mesh, scene.embree_scene, scene.embree_occluded, p, ng, wi, light_p, light_n,
                             is_env)
