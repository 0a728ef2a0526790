"""Exact Fresnel equations for dielectrics and conductors (unpolarized)."""
import warp as wp


@wp.struct
class FresnelDielectric:
    r: float        # reflectance
    cos_t: float    # signed cosine of the refracted direction (opposite sign to cos_i)
    eta_it: float   # relative IOR: transmitted side over incident side
    eta_ti: float   # its inverse


@wp.func
def fresnel_dielectric(cos_i: float, eta: float) -> FresnelDielectric:
    """eta = interior IOR / exterior IOR; cos_i > 0 means incident from the exterior."""
    outside = cos_i >= 0.0
    eta_it = wp.where(outside, eta, 1.0 / eta)
    eta_ti = wp.where(outside, 1.0 / eta, eta)
    cos_t_sqr = 1.0 - eta_ti * eta_ti * (1.0 - cos_i * cos_i)
    abs_cos_i = wp.abs(cos_i)
    abs_cos_t = wp.sqrt(wp.max(cos_t_sqr, 0.0))
    res = FresnelDielectric()
    res.eta_it = eta_it
    res.eta_ti = eta_ti
    if eta == 1.0:
        res.r = 0.0
        res.cos_t = -cos_i
        return res
    a_s = (abs_cos_i - eta_it * abs_cos_t) / (abs_cos_i + eta_it * abs_cos_t)
    a_p = (abs_cos_t - eta_it * abs_cos_i) / (abs_cos_t + eta_it * abs_cos_i)
    r = 0.5 * (a_s * a_s + a_p * a_p)
    if cos_t_sqr <= 0.0:
        r = 1.0  # total internal reflection
        abs_cos_t = 0.0
    res.r = r
    res.cos_t = wp.where(outside, -abs_cos_t, abs_cos_t)
    return res


@wp.func
def fresnel_conductor_channel(cos_i: float, eta: float, k: float) -> float:
    c2 = cos_i * cos_i
    s2 = 1.0 - c2
    eta2 = eta * eta
    k2 = k * k
    t0 = eta2 - k2 - s2
    a2pb2 = wp.sqrt(wp.max(t0 * t0 + 4.0 * eta2 * k2, 0.0))
    a = wp.sqrt(wp.max(0.5 * (a2pb2 + t0), 0.0))
    t1 = a2pb2 + c2
    t2 = 2.0 * cos_i * a
    rs = (t1 - t2) / (t1 + t2)
    t3 = c2 * a2pb2 + s2 * s2
    t4 = t2 * s2
    rp = rs * (t3 - t4) / (t3 + t4)
    return 0.5 * (rs + rp)


@wp.func
def fresnel_conductor(cos_i: float, eta: wp.vec3, k: wp.vec3) -> wp.vec3:
    c = wp.clamp(wp.abs(cos_i), 0.0, 1.0)
    return wp.vec3(
        fresnel_conductor_channel(c, eta[0], k[0]),
        fresnel_conductor_channel(c, eta[1], k[1]),
        fresnel_conductor_channel(c, eta[2], k[2]),
    )
