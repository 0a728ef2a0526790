"""Dielectrics (Mitsuba's `dielectric`, `thindielectric`, `roughdielectric`): Fresnel-weighted
reflection and refraction, chosen by u_lobe with the Fresnel reflectance as its probability.
Radiance is scaled by 1/eta^2 on refraction (radiance transport, as Mitsuba)."""
import warp as wp

from ..fresnel import fresnel_dielectric
from ..microfacet import microfacet_D, microfacet_G, microfacet_pdf, microfacet_sample
from ..types import LOBE_DELTA_REFLECTION, LOBE_DELTA_TRANSMISSION, LOBE_GLOSSY_REFLECTION, LOBE_GLOSSY_TRANSMISSION
from .material import BSDFSample, Material, delta_sample, invalid_sample, microfacet_of, reflect_about, reflect_local

DIELECTRIC_LOBES = LOBE_DELTA_REFLECTION | LOBE_DELTA_TRANSMISSION
ROUGHDIELECTRIC_LOBES = LOBE_GLOSSY_REFLECTION | LOBE_GLOSSY_TRANSMISSION


@wp.func
def dielectric_sample(mat: Material, wi: wp.vec3, u_lobe: float, u: wp.vec2) -> BSDFSample:
    fr = fresnel_dielectric(wi[2], mat.ior)
    s = invalid_sample()
    if u_lobe <= fr.r:
        return delta_sample(s, reflect_local(wi), fr.r, mat.specular_reflectance, LOBE_DELTA_REFLECTION)
    s.eta = fr.eta_it
    return delta_sample(s, wp.vec3(-fr.eta_ti * wi[0], -fr.eta_ti * wi[1], fr.cos_t), 1.0 - fr.r,
                        mat.specular_transmittance * (fr.eta_ti * fr.eta_ti), LOBE_DELTA_TRANSMISSION)


@wp.func
def thindielectric_sample(mat: Material, wi: wp.vec3, u_lobe: float, u: wp.vec2) -> BSDFSample:
    fr = fresnel_dielectric(wp.abs(wi[2]), mat.ior)
    r = fr.r
    if r < 1.0:
        t = 1.0 - r
        r = r + t * t * r / (1.0 - r * r)  # inter-reflections inside the slab
    s = invalid_sample()
    if u_lobe <= r:
        return delta_sample(s, reflect_local(wi), r, mat.specular_reflectance, LOBE_DELTA_REFLECTION)
    return delta_sample(s, -wi, 1.0 - r, mat.specular_transmittance, LOBE_DELTA_TRANSMISSION)


@wp.func
def roughdielectric_half_vector(mat: Material, wi: wp.vec3, wo: wp.vec3) -> wp.vec3:
    reflect = wi[2] * wo[2] > 0.0
    eta = wp.where(wi[2] > 0.0, mat.ior, 1.0 / mat.ior)
    m = wp.normalize(wi + wo * wp.where(reflect, 1.0, eta))
    return m * wp.where(m[2] >= 0.0, 1.0, -1.0)


@wp.func
def roughdielectric_eval(mat: Material, wi: wp.vec3, wo: wp.vec3) -> wp.vec3:
    cos_i = wi[2]
    cos_o = wo[2]
    if cos_i == 0.0 or cos_o == 0.0:
        return wp.vec3(0.0)
    reflect = cos_i * cos_o > 0.0
    eta = wp.where(cos_i > 0.0, mat.ior, 1.0 / mat.ior)
    m = roughdielectric_half_vector(mat, wi, wo)
    # A microfacet must be seen from the same side as its macro-surface by both directions.
    if wp.dot(wi, m) * cos_i <= 0.0 or wp.dot(wo, m) * cos_o <= 0.0:
        return wp.vec3(0.0)
    d = microfacet_of(mat)
    D = microfacet_D(d, m)
    G = microfacet_G(d, wi, wo, m)
    fr = fresnel_dielectric(wp.dot(wi, m), mat.ior)
    if reflect:
        v = fr.r * D * G / (4.0 * wp.abs(cos_i))
        return mat.specular_reflectance * v
    denom = wp.dot(wi, m) + eta * wp.dot(wo, m)
    scale = 1.0 / (eta * eta)  # radiance compression across the interface
    v = wp.abs(scale * (1.0 - fr.r) * D * G * eta * eta * wp.dot(wi, m) * wp.dot(wo, m) / (cos_i * denom * denom))
    return mat.specular_transmittance * v


@wp.func
def roughdielectric_pdf(mat: Material, wi: wp.vec3, wo: wp.vec3) -> float:
    cos_i = wi[2]
    cos_o = wo[2]
    if cos_i == 0.0 or cos_o == 0.0:
        return 0.0
    reflect = cos_i * cos_o > 0.0
    eta = wp.where(cos_i > 0.0, mat.ior, 1.0 / mat.ior)
    m = roughdielectric_half_vector(mat, wi, wo)
    if wp.dot(wi, m) * cos_i <= 0.0 or wp.dot(wo, m) * cos_o <= 0.0:
        return 0.0
    d = microfacet_of(mat)
    s = wp.sign(cos_i)
    prob = microfacet_pdf(d, wi * s, m)
    fr = fresnel_dielectric(wp.dot(wi, m), mat.ior)
    dwh_dwo = float(0.0)
    if reflect:
        dwh_dwo = 1.0 / (4.0 * wp.dot(wo, m))
        prob = prob * fr.r
    else:
        denom = wp.dot(wi, m) + eta * wp.dot(wo, m)
        dwh_dwo = eta * eta * wp.dot(wo, m) / (denom * denom)
        prob = prob * (1.0 - fr.r)
    return wp.abs(prob * dwh_dwo)


@wp.func
def roughdielectric_sample(mat: Material, wi: wp.vec3, u_lobe: float, u: wp.vec2) -> BSDFSample:
    s = invalid_sample()
    m = microfacet_sample(microfacet_of(mat), wi * wp.sign(wi[2]), u)
    fr = fresnel_dielectric(wp.dot(wi, m), mat.ior)
    # A sample on the wrong side of the macro-surface is rejected, not re-scored: the pdf
    # function would read it as the other lobe, whose density is not what produced it.
    if u_lobe <= fr.r:
        s.wo = reflect_about(wi, m)
        s.lobe = LOBE_GLOSSY_REFLECTION
        if s.wo[2] * wi[2] <= 0.0:
            return invalid_sample()
    else:
        s.wo = m * (wp.dot(wi, m) * fr.eta_ti + fr.cos_t) - wi * fr.eta_ti
        s.eta = fr.eta_it
        s.lobe = LOBE_GLOSSY_TRANSMISSION
        if s.wo[2] * wi[2] >= 0.0:
            return invalid_sample()
    return s
