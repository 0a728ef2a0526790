"""One bounce of a path at its vertex x_k, as every path loop takes it (the path tracer, ReSTIR
PT's base path and its replay, Suffix ReSTIR's prefix and its shift): the light connection and
the BSDF sample with their numbers drawn from the path's key at vertex k's slots of the
per-bounce layout (streams.py), and what the scattered ray found (emission, the environment).

The steps themselves are device/path_steps.py's (numbers as arguments); this module is where a
vertex's numbers come from, so that a path and its replay read the same (key, dim) pairs by
construction. `base` offsets a whole path's numbers (the path tracer's sample s starts at
s * DIMS_PER_SAMPLE; a path-reuse path has its own key and starts at 0).
"""
import warp as wp

from .bsdf import Material
from .bump import bump_normal, shadowing_alpha2
from .color import max3
from .intersect import SurfaceHit, offset_origin
from .lights import env_eval, env_pdf, triangle_emission, triangle_light_pdf
from .path_steps import LightConnection, Scatter, connect_to_light, scatter
from .rng import rng_uniform, rng_uniform2
from .sampling import Frame, frame_from_normal, to_local
from .scene_device import SceneDevice, material_index_at, textured_material_of
from .streams import DIM_BSDF_DIR, DIM_BSDF_LOBE, DIM_LIGHT_POINT, DIM_LIGHT_SELECT, DIMS_PER_BOUNCE
from .types import ENV_NONE


@wp.func
def bounce_dim(k: int, slot: int) -> wp.uint32:
    """The dimension of a number drawn at vertex k (slot: DIM_LIGHT_SELECT, ...), from a path's
    first number."""
    return wp.uint32((k + 1) * DIMS_PER_BOUNCE + slot)


@wp.func
def shading_frame(scene: SceneDevice, hit: SurfaceHit, wi: wp.vec3) -> Frame:
    """The frame the BSDF at a hit is evaluated in, wi (world) pointing back along the path: the
    one place the shading normal is decided, so every path loop, shift and target function sees
    the same one. A bump map tilts it (device/bump.py), which is where wi enters."""
    b = scene.material_bump[material_index_at(scene, hit.tri, hit.uv)]
    if b.texture < 0:
        return frame_from_normal(hit.ns)
    return frame_from_normal(bump_normal(scene.positions, scene.uvs, scene.tangents, scene.has_tangents,
                                         scene.textures, scene.tex_pixels, b, hit.tri, hit.bary, hit.uv, hit.ng,
                                         hit.ns, wi))


@wp.func
def material_at(scene: SceneDevice, hit: SurfaceHit, frame: Frame) -> Material:
    """The material a BSDF at the hit is evaluated with, in `frame` (shading_frame's): textures
    resolved (scene_device.textured_material) and, on a bump-mapped surface, the bump map's terms
    for bsdf.py (the unperturbed normal in the tilted frame, the shadowing alpha^2)."""
    i = material_index_at(scene, hit.tri, hit.uv)
    m = textured_material_of(scene, i, hit.uv)
    if m.bumped != 0:  # set in the scene's record of a bump-mapped material
        m.bump_n0 = to_local(frame, hit.ns)
        m.bump_alpha2 = shadowing_alpha2(m.bump_n0, scene.material_bump[i].shadowing)
    return m


@wp.func(inline=True)
def nee_at(scene: SceneDevice, hit: SurfaceHit, mat: Material, frame: Frame, wi: wp.vec3, key: wp.uint32,
           base: wp.uint32, k: int, light_samples: int, strategy: int) -> LightConnection:
    """A light connection at vertex x_k with its numbers (one of `light_samples` per vertex)."""
    return connect_to_light(scene, hit, mat, frame, wi, rng_uniform(key, base + bounce_dim(k, DIM_LIGHT_SELECT)),
                            rng_uniform2(key, base + bounce_dim(k, DIM_LIGHT_POINT)), light_samples, strategy)


@wp.func(inline=True)
def scatter_at(hit: SurfaceHit, mat: Material, frame: Frame, wi: wp.vec3, key: wp.uint32, base: wp.uint32,
               k: int) -> Scatter:
    """The BSDF sample at vertex x_k with its numbers."""
    return scatter(hit, mat, frame, wi, rng_uniform(key, base + bounce_dim(k, DIM_BSDF_LOBE)),
                   rng_uniform2(key, base + bounce_dim(k, DIM_BSDF_DIR)))


@wp.struct
class Found:
    """What a BSDF-sampled ray from x_k found: emission (or the environment), the light pdf of
    that point from x_k (solid angle), the segment x_k -> hit (unit direction and length, from
    rc_criteria.segment; length 0 for the environment)."""
    Le: wp.vec3
    p_light: float
    dir: wp.vec3
    dist: float
    is_env: int


@wp.func
def segment(p: wp.vec3, ng: wp.vec3, q: wp.vec3) -> wp.vec4:
    """(unit direction, length) of the path segment from surface point p (geometric normal ng) to
    q, measured from p's ray origin (offset off the surface, as the traced ray's was): the base
    path and every shift of it then see the same segment to float precision."""
    o = offset_origin(p, ng, q - p)
    v = q - o
    dist = wp.length(v)
    if dist <= 0.0:
        return wp.vec4(0.0)
    v = v / dist
    return wp.vec4(v[0], v[1], v[2], dist)


@wp.func
def found_along(scene: SceneDevice, hit: SurfaceHit, nh: SurfaceHit, d: wp.vec3) -> Found:
    """The emission the ray from hit along d found at nh (a miss: the environment)."""
    f = Found()
    f.is_env = wp.where(nh.valid == 0, 1, 0)
    if f.is_env != 0:
        if scene.env_kind != ENV_NONE:
            f.Le = env_eval(scene, d)
            f.p_light = env_pdf(scene, d)
    else:
        seg = segment(hit.p, hit.ng, nh.p)
        f.dir = wp.vec3(seg[0], seg[1], seg[2])
        f.dist = seg[3]
        f.Le = triangle_emission(scene, nh.tri, nh.ns, -d)
        if max3(f.Le) > 0.0:
            f.p_light = triangle_light_pdf(scene, nh.tri, nh.ng, d, f.dist)
    return f
