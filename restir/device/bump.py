"""Bump and normal mapping as Mitsuba 3's `bumpmap` and `normalmap` BSDFs do them: a texture
tilts the shading normal, and the wrapped BSDF is evaluated in the tilted frame, with two more
factors that make it a BSDF of the unperturbed surface.

- `bump_normal`: the tilted normal n at a hit, from dp/du, dp/dv, the triangle's tangents (from
  its corner uvs; the Duff basis of ng where the uvs are degenerate).
  - A bump map (`bumpmap`): the texture's luminance is a height field h over the uv; with
    g = scale * grad h, dp/du' = dp/du + ns (g_u - ns . dp/du), likewise dp/dv', and
    n = normalize(dp/du' x dp/dv'), turned to ng's side.
  - A normal map (`normalmap`): the texture's RGB c is a normal 2c - 1 in the frame (s, t, ns),
    s = dp/du made orthogonal to ns and t = ns x s, as Mitsuba 3 and pbrt-v4 read it; `strength`
    multiplies its first two components (glTF's normalTexture.scale). With `uv_handed` (glTF's
    tangent space, MikkTSpace's bitangent sign) t turns to point against dp/dv, toward the
    image's top, on triangles whose uv mapping is mirrored. A triangle with given tangents (a
    glTF file's TANGENT: SceneDevice.tangents, sign w != 0) uses them instead: s is the
    interpolated tangent made orthogonal to ns, and t = w (ns x s), glTF's bitangent.
  `flip_invalid_normals` (Mitsuba's default): where wi lies on different sides of ns and n, n is
  mirrored about ns, so the camera side always sees the front.
- `bump_factor`: directions wo on different sides of ns and n carry nothing (Mitsuba's
  `cos_theta(wo) * cos_theta(perturbed wo) > 0`), and with `use_shadowing_function` (default)
  the rest is weighted by Estevez et al.'s terminator shadowing, 2 / (1 + sqrt(1 + a2 tan^2)),
  tan measured from ns, a2 = min(tan^2(n, ns) / 8, 1). The factor multiplies eval (so a sample's
  weight) and its zero region zeroes the pdf; bsdf.py applies it, from the material's `bump_n0`
  (ns in the tilted frame) and `bump_alpha2`, which bounce.material_at fills at each hit.

Only ns, n and wi decide the frame, so a path, its replay and every shift through the vertex see
one BSDF: the frame is a function of the hit and wi alone (bounce.shading_frame).
"""
import warp as wp

from .sampling import frame_from_normal
from .textures import Texture, texture_eval, texture_grad1

PERTURB_HEIGHT = wp.constant(0)  # Bump.kind: a bump map's height field
PERTURB_NORMAL = wp.constant(1)  # a normal map's tangent-space normals


@wp.struct
class Bump:
    """A material's bump or normal map (SceneDevice.material_bump, one per material)."""
    texture: int        # the height or normal texture; -1: not perturbed
    kind: int           # PERTURB_HEIGHT or PERTURB_NORMAL
    scale: float        # a bump map's `scale` (heights are multiplied by it); a normal map's strength
    uv_handed: int      # a normal map's bitangent follows the uv mapping's orientation (glTF)
    flip_invalid: int   # Mitsuba's `flip_invalid_normals`
    shadowing: int      # Mitsuba's `use_shadowing_function`


@wp.func(inline=False)  # out of line as scene_device.texture_lookup: only bump-mapped hits call it
def bump_normal(positions: wp.array(dtype=wp.vec3), uvs: wp.array(dtype=wp.vec2), tangents: wp.array(dtype=wp.vec4),
                has_tangents: int, textures: wp.array(dtype=Texture), texels: wp.array(dtype=wp.vec3), b: Bump,
                tri: int, bary: wp.vec2, uv: wp.vec2, ng: wp.vec3, ns: wp.vec3, wi: wp.vec3) -> wp.vec3:
    """The tilted shading normal at a hit (triangle, barycentrics, uv, geometric and shading
    normals; the hit's fields, passed apart since SurfaceHit's module needs SceneDevice, which
    holds a Bump), wi (world, toward the previous vertex) deciding the flip of an invalid one."""
    i0 = 3 * tri
    dp0 = positions[i0 + 1] - positions[i0]
    dp1 = positions[i0 + 2] - positions[i0]
    duv0 = uvs[i0 + 1] - uvs[i0]
    duv1 = uvs[i0 + 2] - uvs[i0]
    det = duv0[0] * duv1[1] - duv0[1] * duv1[0]
    dp_du = wp.vec3(0.0)
    dp_dv = wp.vec3(0.0)
    if det != 0.0:
        inv_det = 1.0 / det
        dp_du = (duv1[1] * dp0 - duv0[1] * dp1) * inv_det
        dp_dv = (duv0[0] * dp1 - duv1[0] * dp0) * inv_det
    else:
        f = frame_from_normal(ng)
        dp_du = f.s
        dp_dv = f.t
    n = wp.vec3(0.0)
    if b.kind == PERTURB_NORMAL:
        given = wp.vec4(0.0)
        if has_tangents != 0:
            given = tangents[i0] * bary[0] + tangents[i0 + 1] * bary[1] + tangents[i0 + 2] * (1.0 - bary[0] - bary[1])
        n = normal_map_normal(textures, texels, b, uv, ns, dp_du, dp_dv, given)
    else:
        g = b.scale * texture_grad1(textures, texels, b.texture, uv)
        du = dp_du + ns * (g[0] - wp.dot(ns, dp_du))
        dv = dp_dv + ns * (g[1] - wp.dot(ns, dp_dv))
        n = wp.cross(du, dv)
        if wp.dot(ng, n) < 0.0:
            n = -n
    if b.flip_invalid != 0 and wp.dot(wi, ns) * wp.dot(wi, n) <= 0.0:
        n = 2.0 * wp.dot(n, ns) * ns - n
    ln = wp.length(n)
    if not (ln > 0.0 and ln < 1.0e30):  # zero, overflowed or NaN: Mitsuba keeps the shading normal
        return ns
    return n / ln


@wp.func
def normal_map_normal(textures: wp.array(dtype=Texture), texels: wp.array(dtype=wp.vec3), b: Bump, uv: wp.vec2,
                      ns: wp.vec3, dp_du: wp.vec3, dp_dv: wp.vec3, given: wp.vec4) -> wp.vec3:
    """A normal map's (unnormalized) normal in world space: 2c - 1 in the frame (s, t, ns); the
    frame from the given tangent (xyz, and the bitangent's sign w) where w != 0."""
    c = texture_eval(textures, texels, b.texture, uv)
    along = dp_du
    if given[3] != 0.0:
        along = wp.vec3(given[0], given[1], given[2])
    s = along - ns * wp.dot(ns, along)
    ls = wp.length(s)
    if ls > 0.0:
        s = s / ls
    else:  # the tangent along ns: any tangent (Mitsuba's fallback is as arbitrary)
        s = frame_from_normal(ns).s
    t = wp.cross(ns, s)
    if given[3] < 0.0:
        t = -t
    elif given[3] == 0.0 and b.uv_handed != 0 and wp.dot(t, dp_dv) > 0.0:
        t = -t
    return (b.scale * (2.0 * c[0] - 1.0)) * s + (b.scale * (2.0 * c[1] - 1.0)) * t + (2.0 * c[2] - 1.0) * ns


@wp.func
def shadowing_alpha2(n0: wp.vec3, shadowing: int) -> float:
    """Estevez et al.'s alpha^2 from the angle between the two normals (n0: ns in the tilted
    frame, whose cosine to n is n0.z); 0 (no shadowing) when the bump map turns it off."""
    if shadowing == 0:
        return 0.0
    c2 = n0[2] * n0[2]
    return wp.min(0.125 * wp.max(0.0, 1.0 - c2) / c2, 1.0)


@wp.func
def bump_factor(n0: wp.vec3, alpha2: float, wo: wp.vec3) -> float:
    """What the bump map multiplies f(wi, wo) |cos| by, wo in the tilted frame: 0 where wo lies on
    different sides of n and ns, else the shadowing term (1 without it)."""
    c0 = wp.dot(wo, n0)
    if c0 * wo[2] <= 0.0:
        return 0.0
    if alpha2 == 0.0:
        return 1.0
    tan2 = wp.max(0.0, 1.0 - c0 * c0) / (c0 * c0)
    return 2.0 / (1.0 + wp.sqrt(1.0 + alpha2 * tan2))
