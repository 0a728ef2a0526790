"""Beckmann and GGX microfacet distributions (Mitsuba's conventions, anisotropic alphas).

Sampling: GGX samples visible normals (Heitz 2018). Beckmann samples D(m)*cos(theta_m); its
Smith G1 uses Walter's rational fit (as Mitsuba does), so sampling by that exact density keeps
pdf and sampler consistent, which a visible-normal sampler with an approximate G1 would not.
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
def microfacet_pdf(d: Microfacet, wi: wp.vec3, m: wp.vec3) -> float:
    """Density of the sampled normal m given wi (wi in the upper hemisphere)."""
    if d.kind == MICROFACET_BECKMANN:
        return microfacet_D(d, m) * wp.max(m[2], 0.0)
    if wi[2] <= 0.0:
        return 0.0
    return microfacet_G1(d, wi, m) * wp.max(wp.dot(wi, m), 0.0) * microfacet_D(d, m) / wi[2]


@wp.func
def sample_beckmann(d: Microfacet, u: wp.vec2) -> wp.vec3:
    phi = 2.0 * PI * u[1]
    cos_phi = wp.cos(phi)
    sin_phi = wp.sin(phi)
    alpha2 = d.alpha_u * d.alpha_u
    if d.alpha_u != d.alpha_v:
        # Anisotropic: phi distributed as atan(alpha_v/alpha_u * tan(2 pi u)).
        phi = wp.atan(d.alpha_v / d.alpha_u * wp.tan(PI + 2.0 * PI * u[1])) + PI * wp.floor(2.0 * u[1] + 0.5)
        cos_phi = wp.cos(phi)
        sin_phi = wp.sin(phi)
        alpha2 = 1.0 / (cos_phi * cos_phi / (d.alpha_u * d.alpha_u) + sin_phi * sin_phi / (d.alpha_v * d.alpha_v))
    tan2 = -alpha2 * wp.log(1.0 - u[0])
    cos_t = 1.0 / wp.sqrt(1.0 + tan2)
    sin_t = wp.sqrt(wp.max(0.0, 1.0 - cos_t * cos_t))
    return wp.vec3(sin_t * cos_phi, sin_t * sin_phi, cos_t)


@wp.func
def sample_ggx_visible(d: Microfacet, wi: wp.vec3, u: wp.vec2) -> wp.vec3:
    vh = wp.normalize(wp.vec3(d.alpha_u * wi[0], d.alpha_v * wi[1], wi[2]))
    lensq = vh[0] * vh[0] + vh[1] * vh[1]
    t1v = wp.vec3(1.0, 0.0, 0.0)
    if lensq > 0.0:
        t1v = wp.vec3(-vh[1], vh[0], 0.0) / wp.sqrt(lensq)
    t2v = wp.cross(vh, t1v)
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
        return sample_beckmann(d, u)
    return sample_ggx_visible(d, wi, u)
