"""Native ray queries: Embree 4 on the CPU, Warp's BVH on CUDA (and on the CPU as a fallback).

The snippets are compiled into every kernel that traces. On CUDA (`__CUDA_ARCH__`) they call
Warp's C++ `mesh_query_ray`; on the host they call Embree through function pointers handed in
as integers (restir/embree.py loads the library and builds the scene), or Warp's BVH when no
Embree scene is given (scene pointer 0). Results come back as a vec4 because native functions
cannot return structs: (t, Warp barycentric u, Warp barycentric v, triangle index), t < 0 on a
miss. The triangle index travels as a float: exact below 2^24 triangles (checked on the host).
"""
import warp as wp

_EMBREE_RAY = r"""
    struct alignas(16) RestirRayHit {
        float org_x, org_y, org_z, tnear;
        float dir_x, dir_y, dir_z, time;
        float tfar;
        unsigned int mask, id, flags;
        float ng_x, ng_y, ng_z, u, v;
        unsigned int prim_id, geom_id;
        unsigned int inst_id[16];  // room for any RTC_MAX_INSTANCE_LEVEL_COUNT and instPrimID
    };
    RestirRayHit rh;
    rh.org_x = start[0]; rh.org_y = start[1]; rh.org_z = start[2]; rh.tnear = 0.0f;
    rh.dir_x = dir[0]; rh.dir_y = dir[1]; rh.dir_z = dir[2]; rh.time = 0.0f;
    rh.tfar = max_t; rh.mask = 0xFFFFFFFFu; rh.id = 0u; rh.flags = 0u;
    rh.prim_id = 0xFFFFFFFFu; rh.geom_id = 0xFFFFFFFFu;
    for (int k = 0; k < 16; ++k) rh.inst_id[k] = 0xFFFFFFFFu;
"""

_CLOSEST = r"""
#if defined(__CUDA_ARCH__)
    float t, u, v, sign; wp::vec3 n; int face;
    if (wp::mesh_query_ray(mesh, start, dir, max_t, t, u, v, sign, n, face))
        return wp::vec4(t, u, v, (float)face);
    return wp::vec4(-1.0f, 0.0f, 0.0f, 0.0f);
#else
    if (embree_scene == 0) {
        float t, u, v, sign; wp::vec3 n; int face;
        if (wp::mesh_query_ray(mesh, start, dir, max_t, t, u, v, sign, n, face))
            return wp::vec4(t, u, v, (float)face);
        return wp::vec4(-1.0f, 0.0f, 0.0f, 0.0f);
    }
""" + _EMBREE_RAY + r"""
    typedef void (*RestirIntersectFn)(void*, void*, void*);
    ((RestirIntersectFn)(size_t)embree_fn)((void*)(size_t)embree_scene, &rh, nullptr);
    if (rh.geom_id == 0xFFFFFFFFu)
        return wp::vec4(-1.0f, 0.0f, 0.0f, 0.0f);
    // Embree: p = (1-u-v) p0 + u p1 + v p2; Warp: p = u p0 + v p1 + (1-u-v) p2. A geometry's ID is
    // its first triangle (restir/embree.py), so the triangle is geom_id + prim_id.
    return wp::vec4(rh.tfar, 1.0f - rh.u - rh.v, rh.u, (float)(rh.geom_id + rh.prim_id));
#endif
"""

_OCCLUDED = r"""
#if defined(__CUDA_ARCH__)
    return wp::mesh_query_ray_anyhit(mesh, start, dir, max_t);
#else
    if (embree_scene == 0)
        return wp::mesh_query_ray_anyhit(mesh, start, dir, max_t);
""" + _EMBREE_RAY + r"""
    typedef void (*RestirOccludedFn)(void*, void*, void*);
    ((RestirOccludedFn)(size_t)embree_fn)((void*)(size_t)embree_scene, &rh, nullptr);
    return rh.tfar < 0.0f;  // Embree sets tfar to -inf when the ray is blocked
#endif
"""


@wp.func_native(_CLOSEST)
def native_closest_hit(mesh: wp.uint64, embree_scene: wp.uint64, embree_fn: wp.uint64,
                       start: wp.vec3, dir: wp.vec3, max_t: float) -> wp.vec4:
    ...


@wp.func_native(_OCCLUDED)
def native_occluded(mesh: wp.uint64, embree_scene: wp.uint64, embree_fn: wp.uint64,
                    start: wp.vec3, dir: wp.vec3, max_t: float) -> bool:
    ...
