"""SceneDevice: everything a kernel needs to know about the scene, in one @wp.struct.

Triangles are stored un-indexed (corner c of triangle t is element 3t+c), so per-corner
normals and uvs need no second index buffer.
"""
import warp as wp

from .bsdf import Material
from .bump import Bump
from .delta_lights import DeltaLight
from .rng import hash_combine, hash_u32, u32_to_unit_float
from .textures import Texture, scalar_of, texture_eval
from .types import ROUGHNESS_SQRT, ROUGHNESS_SQUARED

vec8i = wp.types.vector(length=8, dtype=wp.int32)
# below this GGX alpha a textured roughness is held (pbrt-v4 would switch to a smooth lobe there)
MIN_TEXTURED_ALPHA = wp.constant(1.0e-4)


@wp.struct
class SceneDevice:
    mesh: wp.uint64                       # Warp BVH over all triangles
    embree_scene: wp.uint64               # Embree scene handle (CPU), 0: trace with Warp's BVH
    embree_intersect: wp.uint64           # address of rtcIntersect1
    embree_occluded: wp.uint64            # address of rtcOccluded1
    positions: wp.array(dtype=wp.vec3)    # 3 per triangle
    normals: wp.array(dtype=wp.vec3)      # 3 per triangle (shading normals; unused where tri_smooth=0)
    uvs: wp.array(dtype=wp.vec2)          # 3 per triangle
    tangents: wp.array(dtype=wp.vec4)     # 3 per triangle where has_tangents (normal maps' given frames), else 1
    has_tangents: int
    tri_smooth: wp.array(dtype=wp.int32)  # 1: interpolate `normals`; 0: flat (geometric) shading
    tri_material: wp.array(dtype=wp.int32)
    tri_emission: wp.array(dtype=wp.vec3)  # area-emitter radiance (front side), 0 if not emissive
    # 1: the triangle's radiance leaves both sides (read only where num_twosided_emitters > 0;
    # one element when there are none)
    tri_emit_twosided: wp.array(dtype=wp.int32)
    num_twosided_emitters: int
    tri_light_pdf: wp.array(dtype=float)   # P(select triangle) / area: NEE density in area measure
    materials: wp.array(dtype=Material)
    # per material, the texture index of reflectance, specular_reflectance, specular_transmittance,
    # opacity, roughness, mixture amount, metallic (scene.py TEXTURED_PARAMETERS, in that order;
    # the eighth is unused); -1: the material's constant holds
    material_textures: wp.array(dtype=vec8i)
    # per material: a mixture's two materials (-1, -1 for any other) and its constant amount
    material_mix: wp.array(dtype=wp.vec2i)
    material_mix_amount: wp.array(dtype=float)
    num_mixtures: int                     # 0: material_index_at is the triangle's material, read no further
    material_bump: wp.array(dtype=Bump)   # per material, its bump map (texture -1: none)
    # The lights other than the environment, chosen in proportion to power by one Walker alias
    # table: light_tri holds the emissive triangles first (num_tri_lights of them), then the delta
    # lights' identities (LIGHT_DELTA_BASE - i for delta light i, types.py)
    light_tri: wp.array(dtype=wp.int32)
    light_prob: wp.array(dtype=float)
    light_alias: wp.array(dtype=wp.int32)
    num_tri_lights: int
    delta_lights: wp.array(dtype=DeltaLight)
    delta_light_pmf: wp.array(dtype=float)  # P(select delta light i | not the environment)
    num_delta_lights: int
    # Environment: constant or lat-long map, importance-sampled by a 2-D piecewise-constant pdf.
    env_kind: int
    env_radiance: wp.vec3                  # constant emitter radiance / envmap scale
    env_to_local: wp.mat33                 # world -> envmap frame
    env_to_world: wp.mat33
    env_width: int
    env_height: int
    env_pixels: wp.array(dtype=wp.vec3)    # row-major, top row first
    env_marginal_cdf: wp.array(dtype=float)     # height+1
    env_conditional_cdf: wp.array(dtype=float)  # height * (width+1)
    env_select_prob: float                 # P(NEE picks the environment)
    # Textures (device/textures.py): their records, and every bitmap's texels packed in one array
    textures: wp.array(dtype=Texture)
    tex_pixels: wp.array(dtype=wp.vec3)


@wp.func(inline=False)
def texture_lookup(textures: wp.array(dtype=Texture), texels: wp.array(dtype=wp.vec3), tex: int, uv: wp.vec2) -> wp.vec3:
    """texture_eval kept out of line. With it and bump.bump_normal out of line, material_at becomes
    small enough to be inlined at the path vertices of the reuse passes; out of line, it copied
    SceneDevice at every call (docs/changelog.md#speed-llvms-inline-threshold-40000). A textured hit pays
    a call instead."""
    return texture_eval(textures, texels, tex, uv)


@wp.func
def texture_or_constant(scene: SceneDevice, tex: int, uv: wp.vec2, constant: wp.vec3) -> wp.vec3:
    if tex >= 0:
        return texture_lookup(scene.textures, scene.tex_pixels, tex, uv)
    return constant


@wp.func
def material_index_at(scene: SceneDevice, tri: int, uv: wp.vec2) -> int:
    """The material at a surface point: the triangle's, or for a mixture (pbrt-v4's `mix`) one of
    its two, the second where a hash of the point (the triangle and its uv) falls below the amount,
    as pbrt-v4 chooses by a hash of the point. A deterministic function of the point, so every
    path loop, shift and target function sees the same material there; averaged over a pixel's
    points the choice is the blend (1 - amount) f_a + amount f_b."""
    i = scene.tri_material[tri]
    if scene.num_mixtures == 0:
        return i
    mix = scene.material_mix[i]
    if mix[0] < 0:
        return i
    amount = scene.material_mix_amount[i]
    tex = scene.material_textures[i][5]
    if tex >= 0:
        amount = scalar_of(texture_lookup(scene.textures, scene.tex_pixels, tex, uv))
    h = hash_combine(hash_u32(wp.uint32(tri)), wp.uint32(int(wp.clamp(uv[0], -1.0e6, 1.0e6) * 1048576.0)))
    h = hash_combine(h, wp.uint32(int(wp.clamp(uv[1], -1.0e6, 1.0e6) * 1048576.0)))
    if u32_to_unit_float(h) < amount:
        return mix[1]
    return mix[0]


@wp.func
def textured_material(scene: SceneDevice, tri: int, uv: wp.vec2) -> Material:
    """The material at the point with textured parameters resolved at uv: the one place textures
    are read (a BSDF sees constants), so a parameter becomes texturable here and in the loader
    (scene.py `spectrum`), not in every material kind. What a BSDF is evaluated with is
    bounce.material_at's, which adds the bump map's terms to this."""
    return textured_material_of(scene, material_index_at(scene, tri, uv), uv)


@wp.func
def textured_material_of(scene: SceneDevice, i: int, uv: wp.vec2) -> Material:
    """Material i with its textured parameters resolved at uv (textured_material, the index known)."""
    m = scene.materials[i]
    tex = scene.material_textures[i]
    m.reflectance = texture_or_constant(scene, tex[0], uv, m.reflectance)
    m.specular_reflectance = texture_or_constant(scene, tex[1], uv, m.specular_reflectance)
    m.specular_transmittance = texture_or_constant(scene, tex[2], uv, m.specular_transmittance)
    if tex[3] >= 0:  # a mask's opacity: the texture's eval_1, clipped to [0, 1] as in Mitsuba
        m.opacity = wp.clamp(scalar_of(texture_lookup(scene.textures, scene.tex_pixels, tex[3], uv)), 0.0, 1.0)
    if tex[4] >= 0:  # an isotropic roughness: alpha, pbrt-v4's roughness (sqrt) or glTF's (square)
        r = wp.max(scalar_of(texture_lookup(scene.textures, scene.tex_pixels, tex[4], uv)), 0.0)
        if m.roughness_remap == ROUGHNESS_SQRT:
            r = wp.sqrt(r)
        elif m.roughness_remap == ROUGHNESS_SQUARED:
            r = r * r
        m.alpha_u = wp.max(r, MIN_TEXTURED_ALPHA)
        m.alpha_v = m.alpha_u
    if tex[6] >= 0:  # glTF's metallic
        m.metallic = wp.clamp(scalar_of(texture_lookup(scene.textures, scene.tex_pixels, tex[6], uv)), 0.0, 1.0)
    return m
