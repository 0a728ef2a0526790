"""Beckmann and GGX microfacet distributions (Mitsuba's conventions, anisotropic alphas).

Both sample visible normals: GGX by Heitz (2018); Beckmann by Heitz and d'Eon (2014), the
slope in the incident plane drawn by a safeguarded Newton inversion of its CDF. The *shading*
G1 of Beckmann is Walter's rational fit (as in Mitsuba's eval); the *pdf* of the visible-normal
sampler must be the density it really produces, so it uses the exact Smith G1 (erf form).
"""
import warp as wp

from .types import MICROFACET_BECKMANN, PI


@wp.struct
class Microfacet:
    kind: int
    alpha_u: float
    alpha_v: float


@wp.func
def microfacet_D(d: Microfacet, m: wp.vec3) -> float:
    cos_t = m[2]
    if cos_t <= 0.0:
        return 0.0
    ax = d.alpha_u
    ay = d.alpha_v
    if d.kind == MICROFACET_BECKMANN:
        cos2 = cos_t * cos_t
        e = (m[0] * m[0] / (ax * ax) + m[1] * m[1] / (ay * ay)) / cos2
        return wp.exp(-e) / (PI * ax * ay * cos2 * cos2)
    t = m[0] * m[0] / (ax * ax) + m[1] * m[1] / (ay * ay) + cos_t * cos_t
    return 1.0 / (PI * ax * ay * t * t)


@wp.func
def microfacet_G1(d: Microfacet, v: wp.vec3, m: wp.vec3) -> float:
    if wp.dot(v, m) * v[2] <= 0.0:
        return 0.0
    xy_alpha2 = (d.alpha_u * v[0]) * (d.alpha_u * v[0]) + (d.alpha_v * v[1]) * (d.alpha_v * v[1])
    if xy_alpha2 == 0.0:
        return 1.0
    tan_alpha2 = xy_alpha2 / (v[2] * v[2])
    if d.kind == MICROFACET_BECKMANN:
        a = 1.0 / wp.sqrt(tan_alpha2)
        if a >= 1.6:
            return 1.0
        return (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a)
    return 2.0 / (1.0 + wp.sqrt(1.0 + tan_alpha2))


@wp.func
def microfacet_G(d: Microfacet, wi: wp.vec3, wo: wp.vec3, m: wp.vec3) -> float:
    return microfacet_G1(d, wi, m) * microfacet_G1(d, wo, m)


@wp.func
def beckmann_G1_exact(d: Microfacet, v: wp.vec3, m: wp.vec3) -> float:
    """Smith G1 of Beckmann in closed form: 1 / (1 + Lambda(a)), a = 1 / (alpha tan theta)."""
    if wp.dot(v, m) * v[2] <= 0.0:
        return 0.0
    xy_alpha2 = (d.alpha_u * v[0]) * (d.alpha_u * v[0]) + (d.alpha_v * v[1]) * (d.alpha_v * v[1])
    if xy_alpha2 == 0.0:
        return 1.0
    a = wp.abs(v[2]) / wp.sqrt(xy_alpha2)
    lam = 0.5 * (wp.erf(a) - 1.0) + wp.exp(-a * a) / (2.0 * a * wp.sqrt(PI))
    return 1.0 / (1.0 + lam)


@wp.func
def microfacet_pdf(d: Microfacet, wi: wp.vec3, m: wp.vec3) -> float:
    """Density of the visible normal m given wi (wi in the upper hemisphere)."""
    if wi[2] <= 0.0:
        return 0.0
    g1 = float(0.0)
    if d.kind == MICROFACET_BECKMANN:
        g1 = beckmann_G1_exact(d, wi, m)
    else:
        g1 = microfacet_G1(d, wi, m)
    return g1 * wp.max(wp.dot(wi, m), 0.0) * microfacet_D(d, m) / wi[2]


@wp.func
def beckmann_visible_slopes(cos_i: float, u: wp.vec2) -> wp.vec2:
    """Visible slopes of the unit-roughness Beckmann distribution, incident plane along +x."""
    if cos_i > 0.9999:  # normal incidence: the slopes are an isotropic Gaussian
        r = wp.sqrt(-wp.log(wp.max(1.0 - u[0], 1.0e-12)))
        phi = 2.0 * PI * u[1]
        return wp.vec2(r * wp.cos(phi), r * wp.sin(phi))
    sin_i = wp.sqrt(wp.max(0.0, 1.0 - cos_i * cos_i))
    tan_i = sin_i / cos_i
    cot_i = cos_i / sin_i
    # CDF of b = erf(slope): C(b) = k (1 + b + tan_i exp(-erfinv(b)^2) / sqrt(pi)) on [-1, erf(cot_i)]
    lo = float(-1.0)
    hi = wp.erf(cot_i)
    k = 1.0 / (1.0 + hi + tan_i * wp.exp(-cot_i * cot_i) / wp.sqrt(PI))
    target = wp.max(u[0], 1.0e-6)
    theta_i = wp.acos(cos_i)
    fit = 1.0 + theta_i * (-0.876 + theta_i * (0.4265 - 0.0594 * theta_i))  # good first guess
    b = hi - (1.0 + hi) * wp.pow(1.0 - target, fit)
    for _ in range(12):
        if not (b >= lo and b <= hi):
            b = 0.5 * (lo + hi)  # keep Newton inside the bracket
        e = wp.erfinv(b)
        value = k * (1.0 + b + tan_i * wp.exp(-e * e) / wp.sqrt(PI)) - target
        if wp.abs(value) < 1.0e-6:
            break
        if value > 0.0:
            hi = b
        else:
            lo = b
        b = b - value / (k * (1.0 - e * tan_i))
    return wp.vec2(wp.erfinv(b), wp.erfinv(2.0 * wp.clamp(u[1], 1.0e-7, 1.0 - 1.0e-7) - 1.0))


@wp.func
def beckmann_incident_plane(d: Microfacet, wi: wp.vec3) -> wp.vec3:
    """wi stretched to alpha = 1: (its cos theta, and cos phi, sin phi of its incident plane)."""
    ws = wp.normalize(wp.vec3(d.alpha_u * wi[0], d.alpha_v * wi[1], wi[2]))
    sin_s = wp.sqrt(ws[0] * ws[0] + ws[1] * ws[1])
    cos_phi = float(1.0)
    sin_phi = float(0.0)
    if sin_s > 1.0e-7:
        cos_phi = ws[0] / sin_s
        sin_phi = ws[1] / sin_s
    return wp.vec3(ws[2], cos_phi, sin_phi)


@wp.func
def sample_beckmann_visible(d: Microfacet, wi: wp.vec3, u: wp.vec2) -> wp.vec3:
    plane = beckmann_incident_plane(d, wi)
    slope = beckmann_visible_slopes(plane[0], u)
    cos_phi = plane[1]
    sin_phi = plane[2]
    sx = (cos_phi * slope[0] - sin_phi * slope[1]) * d.alpha_u  # rotate, then unstretch
    sy = (sin_phi * slope[0] + cos_phi * slope[1]) * d.alpha_v
    return wp.normalize(wp.vec3(-sx, -sy, 1.0))


@wp.struct
class VisibleFrame:
    """The frame of GGX visible-normal sampling: wi stretched to alpha = 1 (vh) and two tangents."""
    vh: wp.vec3
    t1: wp.vec3
    t2: wp.vec3


@wp.func
def ggx_visible_frame(d: Microfacet, wi: wp.vec3) -> VisibleFrame:
    f = VisibleFrame()
    f.vh = wp.normalize(wp.vec3(d.alpha_u * wi[0], d.alpha_v * wi[1], wi[2]))
    lensq = f.vh[0] * f.vh[0] + f.vh[1] * f.vh[1]
    f.t1 = wp.vec3(1.0, 0.0, 0.0)
    if lensq > 0.0:
        f.t1 = wp.vec3(-f.vh[1], f.vh[0], 0.0) / wp.sqrt(lensq)
    f.t2 = wp.cross(f.vh, f.t1)
    return f


@wp.func
def sample_ggx_visible(d: Microfacet, wi: wp.vec3, u: wp.vec2) -> wp.vec3:
    fr = ggx_visible_frame(d, wi)
    vh = fr.vh
    t1v = fr.t1
    t2v = fr.t2
    r = wp.sqrt(u[0])
    phi = 2.0 * PI * u[1]
    t1 = r * wp.cos(phi)
    t2 = r * wp.sin(phi)
    s = 0.5 * (1.0 + vh[2])
    t2 = (1.0 - s) * wp.sqrt(wp.max(0.0, 1.0 - t1 * t1)) + s * t2
    nh = t1 * t1v + t2 * t2v + wp.sqrt(wp.max(0.0, 1.0 - t1 * t1 - t2 * t2)) * vh
    return wp.normalize(wp.vec3(d.alpha_u * nh[0], d.alpha_v * nh[1], wp.max(1.0e-7, nh[2])))


@wp.func
def microfacet_sample(d: Microfacet, wi: wp.vec3, u: wp.vec2) -> wp.vec3:
    if d.kind == MICROFACET_BECKMANN:
        return sample_beckmann_visible(d, wi, u)
    return sample_ggx_visible(d, wi, u)


@wp.func
def ggx_visible_to_square(d: Microfacet, wi: wp.vec3, m: wp.vec3) -> wp.vec2:
    """The inverse of sample_ggx_visible: the u that samples the normal m given wi."""
    fr = ggx_visible_frame(d, wi)
    nh = wp.normalize(wp.vec3(m[0] / d.alpha_u, m[1] / d.alpha_v, m[2]))  # undo the unstretch
    t1 = wp.dot(nh, fr.t1)
    s = 0.5 * (1.0 + fr.vh[2])
    t2 = (wp.dot(nh, fr.t2) - (1.0 - s) * wp.sqrt(wp.max(0.0, 1.0 - t1 * t1))) / s
    phi = wp.atan2(t2, t1)
    if phi < 0.0:
        phi = phi + 2.0 * PI
    return wp.vec2(t1 * t1 + t2 * t2, phi / (2.0 * PI))


@wp.func
def beckmann_visible_to_square(d: Microfacet, wi: wp.vec3, m: wp.vec3) -> wp.vec2:
    """The inverse of sample_beckmann_visible: the u that samples the normal m given wi (the
    visible-slope CDF evaluated where the sampler inverts it by Newton's method)."""
    plane = beckmann_incident_plane(d, wi)
    cos_phi = plane[1]
    sin_phi = plane[2]
    a = -m[0] / m[2] / d.alpha_u  # stretched slopes, rotated back into the incident plane
    b = -m[1] / m[2] / d.alpha_v
    s0 = cos_phi * a + sin_phi * b
    s1 = -sin_phi * a + cos_phi * b
    cos_i = plane[0]
    if cos_i > 0.9999:
        phi = wp.atan2(s1, s0)
        if phi < 0.0:
            phi = phi + 2.0 * PI
        return wp.vec2(1.0 - wp.exp(-(s0 * s0 + s1 * s1)), phi / (2.0 * PI))
    sin_i = wp.sqrt(wp.max(0.0, 1.0 - cos_i * cos_i))
    tan_i = sin_i / cos_i
    cot_i = cos_i / sin_i
    k = 1.0 / (1.0 + wp.erf(cot_i) + tan_i * wp.exp(-cot_i * cot_i) / wp.sqrt(PI))
    u0 = k * (1.0 + wp.erf(s0) + tan_i * wp.exp(-s0 * s0) / wp.sqrt(PI))
    return wp.vec2(u0, 0.5 * (wp.erf(s1) + 1.0))


@wp.func
def microfacet_sample_to_square(d: Microfacet, wi: wp.vec3, m: wp.vec3) -> wp.vec2:
    """The inverse of microfacet_sample (m a visible normal for wi): for primary-sample-space
    tools and tests, such as the finite-difference Jacobians of ReSTIR PT's shifts."""
    if d.kind == MICROFACET_BECKMANN:
        return beckmann_visible_to_square(d, wi, m)
    return ggx_visible_to_square(d, wi, m)
