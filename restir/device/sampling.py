"""Sampling warps as (sample, pdf, invert) triads, plus orthonormal frames.

Conventions follow Mitsuba's warp.h: `square_to_X(u)` maps [0,1)^n to the domain, `X_pdf`
gives the density in the domain's natural measure, `X_to_square` inverts the sample map.
"""
import warp as wp

from .types import INV_FOUR_PI, INV_PI, PI


# ----------------------------------------------------------------------------- frames
@wp.struct
class Frame:
    s: wp.vec3
    t: wp.vec3
    n: wp.vec3


@wp.func
def frame_from_normal(n: wp.vec3) -> Frame:
    # Duff et al. 2017, "Building an orthonormal basis, revisited": branch-free, continuous.
    sign = wp.where(n[2] >= 0.0, 1.0, -1.0)
    a = -1.0 / (sign + n[2])
    b = n[0] * n[1] * a
    f = Frame()
    f.s = wp.vec3(1.0 + sign * n[0] * n[0] * a, sign * b, -sign * n[0])
    f.t = wp.vec3(b, sign + n[1] * n[1] * a, -n[1])
    f.n = n
    return f


@wp.func
def to_local(f: Frame, v: wp.vec3) -> wp.vec3:
    return wp.vec3(wp.dot(v, f.s), wp.dot(v, f.t), wp.dot(v, f.n))


@wp.func
def to_world(f: Frame, v: wp.vec3) -> wp.vec3:
    return f.s * v[0] + f.t * v[1] + f.n * v[2]


# ----------------------------------------------------------------------------- disks and hemispheres
@wp.func
def square_to_uniform_disk_concentric(u: wp.vec2) -> wp.vec2:
    x = 2.0 * u[0] - 1.0
    y = 2.0 * u[1] - 1.0
    r = float(0.0)
    phi = float(0.0)
    if x == 0.0 and y == 0.0:
        return wp.vec2(0.0, 0.0)
    if x * x > y * y:
        r = x
        phi = (PI / 4.0) * (y / x)
    else:
        r = y
        phi = (PI / 2.0) - (PI / 4.0) * (x / y)
    return wp.vec2(r * wp.cos(phi), r * wp.sin(phi))


@wp.func
def uniform_disk_concentric_to_square(p: wp.vec2) -> wp.vec2:
    quadrant = wp.abs(p[0]) < wp.abs(p[1])
    r_sign = wp.where(quadrant, p[1], p[0])
    r = wp.sqrt(p[0] * p[0] + p[1] * p[1])
    r = wp.where(r_sign < 0.0, -r, r)
    phi = wp.atan2(p[1] * wp.sign(r_sign), p[0] * wp.sign(r_sign))
    t = 4.0 / PI * phi
    t = wp.where(quadrant, 2.0 - t, t)
    t = t * r
    a = wp.where(quadrant, t, r)
    b = wp.where(quadrant, r, t)
    return wp.vec2((a + 1.0) * 0.5, (b + 1.0) * 0.5)


@wp.func
def square_to_cosine_hemisphere(u: wp.vec2) -> wp.vec3:
    p = square_to_uniform_disk_concentric(u)
    z = wp.sqrt(wp.max(0.0, 1.0 - p[0] * p[0] - p[1] * p[1]))
    return wp.vec3(p[0], p[1], z)


@wp.func
def cosine_hemisphere_pdf(v: wp.vec3) -> float:
    return wp.where(v[2] > 0.0, v[2] * INV_PI, 0.0)


@wp.func
def cosine_hemisphere_to_square(v: wp.vec3) -> wp.vec2:
    return uniform_disk_concentric_to_square(wp.vec2(v[0], v[1]))


@wp.func
def square_to_uniform_sphere(u: wp.vec2) -> wp.vec3:
    z = 1.0 - 2.0 * u[1]
    r = wp.sqrt(wp.max(0.0, 1.0 - z * z))
    phi = 2.0 * PI * u[0]
    return wp.vec3(r * wp.cos(phi), r * wp.sin(phi), z)


@wp.func
def uniform_sphere_pdf(v: wp.vec3) -> float:
    return INV_FOUR_PI


@wp.func
def uniform_sphere_to_square(v: wp.vec3) -> wp.vec2:
    phi = wp.atan2(v[1], v[0])
    phi = wp.where(phi < 0.0, phi + 2.0 * PI, phi)
    return wp.vec2(phi / (2.0 * PI), (1.0 - v[2]) * 0.5)


# ----------------------------------------------------------------------------- triangles
@wp.func
def square_to_uniform_triangle(u: wp.vec2) -> wp.vec2:
    """Barycentrics (b1, b2) uniform over the triangle; b0 = 1 - b1 - b2."""
    t = wp.sqrt(1.0 - u[0])
    return wp.vec2(1.0 - t, u[1] * t)


@wp.func
def uniform_triangle_to_square(b: wp.vec2) -> wp.vec2:
    t = 1.0 - b[0]
    return wp.vec2(1.0 - t * t, wp.where(t > 0.0, b[1] / t, 0.0))


# ----------------------------------------------------------------------------- 1-D tent on [-1, 1]
@wp.func
def sample_tent(u: float) -> float:
    return wp.where(u < 0.5, wp.sqrt(2.0 * u) - 1.0, 1.0 - wp.sqrt(2.0 - 2.0 * u))


@wp.func
def tent_pdf(x: float) -> float:
    return wp.max(0.0, 1.0 - wp.abs(x))


@wp.func
def invert_tent(x: float) -> float:
    return wp.where(x < 0.0, 0.5 * (x + 1.0) * (x + 1.0), 1.0 - 0.5 * (1.0 - x) * (1.0 - x))


# ----------------------------------------------------------------------------- discrete (alias table)
@wp.func
def sample_alias(prob: wp.array(dtype=float), alias: wp.array(dtype=wp.int32), u: float) -> int:
    """Walker alias table lookup with one uniform number (scaled and split into bin + coin)."""
    n = prob.shape[0]
    x = u * float(n)
    i = wp.min(int(x), n - 1)
    coin = x - float(i)
    if coin < prob[i]:
        return i
    return int(alias[i])


@wp.func
def sample_cdf(cdf: wp.array(dtype=float), start: int, count: int, u: float) -> int:
    """Binary search in cdf[start : start+count+1] (cdf[start] = 0, cdf[start+count] = 1)."""
    lo = int(0)
    hi = count - 1
    while lo < hi:
        mid = (lo + hi) // 2
        if cdf[start + mid + 1] <= u:
            lo = mid + 1
        else:
            hi = mid
    return lo
