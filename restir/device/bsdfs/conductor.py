"""Conductors (Mitsuba's `conductor` and `roughconductor`): Fresnel reflectance of a complex IOR
(eta + i k) times `specular_reflectance`; the rough one a microfacet lobe (Beckmann or GGX,
visible-normal sampling, microfacet.py)."""
import warp as wp

from ..fresnel import fresnel_conductor
from ..microfacet import microfacet_D, microfacet_G, microfacet_pdf, microfacet_sample
from ..types import LOBE_DELTA_REFLECTION, LOBE_GLOSSY_REFLECTION
from .material import BSDFSample, Material, delta_sample, invalid_sample, microfacet_of, reflect_about, reflect_local

CONDUCTOR_LOBES = LOBE_DELTA_REFLECTION
ROUGHCONDUCTOR_LOBES = LOBE_GLOSSY_REFLECTION


@wp.func
def conductor_sample(mat: Material, wi: wp.vec3, u_lobe: float, u: wp.vec2) -> BSDFSample:
    s = invalid_sample()
    if wi[2] <= 0.0:
        return s
    return delta_sample(s, reflect_local(wi), 1.0, wp.cw_mul(fresnel_conductor(wi[2], mat.eta, mat.k),
                                                             mat.specular_reflectance), LOBE_DELTA_REFLECTION)


@wp.func
def roughconductor_eval(mat: Material, wi: wp.vec3, wo: wp.vec3) -> wp.vec3:
    if wi[2] <= 0.0 or wo[2] <= 0.0:
        return wp.vec3(0.0)
    m = wp.normalize(wi + wo)
    d = microfacet_of(mat)
    v = microfacet_D(d, m) * microfacet_G(d, wi, wo, m) / (4.0 * wi[2])
    F = fresnel_conductor(wp.dot(wi, m), mat.eta, mat.k)
    return wp.cw_mul(F, mat.specular_reflectance) * v


@wp.func
def roughconductor_pdf(mat: Material, wi: wp.vec3, wo: wp.vec3) -> float:
    if wi[2] <= 0.0 or wo[2] <= 0.0:
        return 0.0
    m = wp.normalize(wi + wo)
    d = microfacet_of(mat)
    return microfacet_pdf(d, wi, m) / (4.0 * wp.dot(wo, m))


@wp.func
def roughconductor_sample(mat: Material, wi: wp.vec3, u_lobe: float, u: wp.vec2) -> BSDFSample:
    s = invalid_sample()
    if wi[2] <= 0.0:
        return s
    s.wo = reflect_about(wi, microfacet_sample(microfacet_of(mat), wi, u))
    s.lobe = LOBE_GLOSSY_REFLECTION
    return s
