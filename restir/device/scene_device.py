"""SceneDevice: everything a kernel needs to know about the scene, in one @wp.struct.

Triangles are stored un-indexed (corner c of triangle t is element 3t+c), so per-corner
normals and uvs need no second index buffer.
"""
import warp as wp

from .bsdf import Material


@wp.struct
class SceneDevice:
    mesh: wp.uint64                       # Warp BVH over all triangles
    embree_scene: wp.uint64               # Embree scene handle (CPU), 0: trace with Warp's BVH
    embree_intersect: wp.uint64           # address of rtcIntersect1
    embree_occluded: wp.uint64            # address of rtcOccluded1
    positions: wp.array(dtype=wp.vec3)    # 3 per triangle
    normals: wp.array(dtype=wp.vec3)      # 3 per triangle (shading normals; unused where tri_smooth=0)
    uvs: wp.array(dtype=wp.vec2)          # 3 per triangle
    tri_smooth: wp.array(dtype=wp.int32)  # 1: interpolate `normals`; 0: flat (geometric) shading
    tri_material: wp.array(dtype=wp.int32)
    tri_emission: wp.array(dtype=wp.vec3)  # area-emitter radiance (front side), 0 if not emissive
    tri_light_pdf: wp.array(dtype=float)   # P(select triangle) / area: NEE density in area measure
    materials: wp.array(dtype=Material)
    # Emissive triangles, chosen in proportion to power by a Walker alias table.
    light_tri: wp.array(dtype=wp.int32)
    light_prob: wp.array(dtype=float)
    light_alias: wp.array(dtype=wp.int32)
    num_tri_lights: int
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
    # Textures (RGB, bilinear-free nearest lookup), packed into one array.
    tex_pixels: wp.array(dtype=wp.vec3)
    tex_offset: wp.array(dtype=wp.int32)
    tex_width: wp.array(dtype=wp.int32)
    tex_height: wp.array(dtype=wp.int32)


@wp.func
def texel(scene: SceneDevice, tex: int, x: int, y: int) -> wp.vec3:
    w = scene.tex_width[tex]
    h = scene.tex_height[tex]
    xi = ((x % w) + w) % w
    yi = ((y % h) + h) % h
    return scene.tex_pixels[scene.tex_offset[tex] + yi * w + xi]


@wp.func
def texture_bilinear(scene: SceneDevice, tex: int, uv: wp.vec2) -> wp.vec3:
    """Mitsuba's bitmap lookup: uv (0,0) is the first (top-left) texel, repeat wrapping."""
    x = uv[0] * float(scene.tex_width[tex]) - 0.5
    y = uv[1] * float(scene.tex_height[tex]) - 0.5
    x0 = wp.floor(x)
    y0 = wp.floor(y)
    fx = x - x0
    fy = y - y0
    xi = int(x0)
    yi = int(y0)
    a = texel(scene, tex, xi, yi) * (1.0 - fx) + texel(scene, tex, xi + 1, yi) * fx
    b = texel(scene, tex, xi, yi + 1) * (1.0 - fx) + texel(scene, tex, xi + 1, yi + 1) * fx
    return a * (1.0 - fy) + b * fy


@wp.func
def material_at(scene: SceneDevice, tri: int, uv: wp.vec2) -> Material:
    """The triangle's material with textured parameters resolved at uv."""
    m = scene.materials[scene.tri_material[tri]]
    if m.reflectance_tex >= 0:
        m.reflectance = texture_bilinear(scene, m.reflectance_tex, uv)
    return m
