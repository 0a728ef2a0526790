"""Textures on the device: Mitsuba 3's `bitmap` (nearest or bilinear lookup; repeat, mirror or clamp
wrapping) and `checkerboard`, each with its `to_uv` transform; one `texture_eval` for every
textured parameter (scene_device.textured_material is its only caller, so a BSDF never reads one), and
`texture_grad1`, the uv gradient of a bitmap's luminance that a bump map (device/bump.py) reads.
"""
import warp as wp

TEX_BITMAP = wp.constant(0)
TEX_CHECKERBOARD = wp.constant(1)

TEX_FILTER_NEAREST = wp.constant(0)
TEX_FILTER_BILINEAR = wp.constant(1)

TEX_WRAP_REPEAT = wp.constant(0)
TEX_WRAP_MIRROR = wp.constant(1)
TEX_WRAP_CLAMP = wp.constant(2)


@wp.struct
class Texture:
    kind: int          # TEX_*
    to_uv: wp.mat33    # affine map of the surface's uv (Mitsuba's 3x3 `to_uv`)
    # bitmap: texels[offset + y * width + x], row y = 0 at the top (uv (0, 0) is its first texel)
    offset: int
    width: int
    height: int
    filter: int        # TEX_FILTER_*
    wrap: int          # TEX_WRAP_*
    # checkerboard: color0 where frac(u) and frac(v) are both above 1/2 or both not, else color1
    color0: wp.vec3
    color1: wp.vec3


@wp.func
def wrap_texel(i: int, n: int, mode: int) -> int:
    if mode == TEX_WRAP_CLAMP:
        return wp.clamp(i, 0, n - 1)
    if mode == TEX_WRAP_MIRROR:
        p = ((i % (2 * n)) + 2 * n) % (2 * n)
        return wp.where(p < n, p, 2 * n - 1 - p)
    return ((i % n) + n) % n


@wp.func
def bitmap_texel(t: Texture, texels: wp.array(dtype=wp.vec3), x: int, y: int) -> wp.vec3:
    return texels[t.offset + wrap_texel(y, t.height, t.wrap) * t.width + wrap_texel(x, t.width, t.wrap)]


@wp.func
def bitmap_eval(t: Texture, texels: wp.array(dtype=wp.vec3), uv: wp.vec2) -> wp.vec3:
    x = uv[0] * float(t.width)
    y = uv[1] * float(t.height)
    if t.filter == TEX_FILTER_NEAREST:
        return bitmap_texel(t, texels, int(wp.floor(x)), int(wp.floor(y)))
    # bilinear between the four texel centres around the point
    x = x - 0.5
    y = y - 0.5
    x0 = wp.floor(x)
    y0 = wp.floor(y)
    fx = x - x0
    fy = y - y0
    xi = int(x0)
    yi = int(y0)
    a = bitmap_texel(t, texels, xi, yi) * (1.0 - fx) + bitmap_texel(t, texels, xi + 1, yi) * fx
    b = bitmap_texel(t, texels, xi, yi + 1) * (1.0 - fx) + bitmap_texel(t, texels, xi + 1, yi + 1) * fx
    return a * (1.0 - fy) + b * fy


@wp.func
def checkerboard_eval(t: Texture, uv: wp.vec2) -> wp.vec3:
    high_u = uv[0] - wp.floor(uv[0]) > 0.5
    high_v = uv[1] - wp.floor(uv[1]) > 0.5
    if high_u == high_v:
        return t.color0
    return t.color1


@wp.func
def texture_eval(textures: wp.array(dtype=Texture), texels: wp.array(dtype=wp.vec3), tex: int,
                 surface_uv: wp.vec2) -> wp.vec3:
    t = textures[tex]
    q = t.to_uv * wp.vec3(surface_uv[0], surface_uv[1], 1.0)
    uv = wp.vec2(q[0], q[1])
    if t.kind == TEX_CHECKERBOARD:
        return checkerboard_eval(t, uv)
    return bitmap_eval(t, texels, uv)


@wp.func
def scalar_of(c: wp.vec3) -> float:
    """A scalar parameter from an RGB texel, as Mitsuba's `eval_1` reads an RGB texture: its
    `luminance` (the exact Rec. 709 weights, which color.luminance rounds to four digits). A bump
    map's height, a mask's opacity."""
    return 0.212671 * c[0] + 0.715160 * c[1] + 0.072169 * c[2]


@wp.func
def texture_grad1(textures: wp.array(dtype=Texture), texels: wp.array(dtype=wp.vec3), tex: int,
                  surface_uv: wp.vec2) -> wp.vec2:
    """d height / d(u, v) of a bilinear bitmap at the surface's uv (Mitsuba's `eval_1_grad`): the
    exact derivative of the bilinear interpolant of the four texels' heights, by the chain rule
    through `to_uv`. Nearest filtering has gradient 0 almost everywhere (as in Mitsuba); the loader
    refuses a checkerboard, whose gradient is 0 or undefined everywhere."""
    t = textures[tex]
    if t.filter == TEX_FILTER_NEAREST:
        return wp.vec2(0.0)
    q = t.to_uv * wp.vec3(surface_uv[0], surface_uv[1], 1.0)
    x = q[0] * float(t.width) - 0.5
    y = q[1] * float(t.height) - 0.5
    x0 = wp.floor(x)
    y0 = wp.floor(y)
    fx = x - x0
    fy = y - y0
    xi = int(x0)
    yi = int(y0)
    f00 = scalar_of(bitmap_texel(t, texels, xi, yi))
    f10 = scalar_of(bitmap_texel(t, texels, xi + 1, yi))
    f01 = scalar_of(bitmap_texel(t, texels, xi, yi + 1))
    f11 = scalar_of(bitmap_texel(t, texels, xi + 1, yi + 1))
    # per texel along x and y, then texels per unit of the texture's uv, then the surface's uv
    # (Mitsuba scales both components by (width, height) after the to_uv product, which differs
    # from this only when to_uv mixes u and v on a non-square image: docs/guide/scenes.md)
    df_dx = (1.0 - fy) * (f10 - f00) + fy * (f11 - f01)
    df_dy = (1.0 - fx) * (f01 - f00) + fx * (f11 - f10)
    gx = df_dx * float(t.width)
    gy = df_dy * float(t.height)
    return wp.vec2(t.to_uv[0, 0] * gx + t.to_uv[1, 0] * gy, t.to_uv[0, 1] * gx + t.to_uv[1, 1] * gy)
