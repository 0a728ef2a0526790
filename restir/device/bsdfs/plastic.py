"""Mitsuba's `plastic` and `roughplastic`: a dielectric coat (ior; rough: a microfacet lobe of
`distribution`, `alpha_u`) over a diffuse base (`reflectance`), with internal scattering folded
into fdr_int and, for the rough coat, a tabulated coat transmittance (scene/coat_tables.py)."""
import warp as wp

from ..fresnel import fresnel_dielectric
from ..microfacet import microfacet_D, microfacet_G, microfacet_pdf, microfacet_sample
from ..sampling import cosine_hemisphere_pdf, square_to_cosine_hemisphere
from ..types import INV_PI, LOBE_DELTA_REFLECTION, LOBE_DIFFUSE_REFLECTION, LOBE_GLOSSY_REFLECTION
from .material import BSDFSample, Material, delta_sample, invalid_sample, microfacet_of, reflect_about, reflect_local

PLASTIC_LOBES = LOBE_DELTA_REFLECTION | LOBE_DIFFUSE_REFLECTION
ROUGHPLASTIC_LOBES = LOBE_GLOSSY_REFLECTION | LOBE_DIFFUSE_REFLECTION


# ----------------------------------------------------------------------------- plastic
@wp.func
def plastic_specular_probability(mat: Material, f_i: float) -> float:
    ps = f_i * mat.specular_sampling_weight
    pd = (1.0 - f_i) * (1.0 - mat.specular_sampling_weight)
    return ps / (ps + pd)


@wp.func
def plastic_eval(mat: Material, wi: wp.vec3, wo: wp.vec3) -> wp.vec3:
    if wi[2] <= 0.0 or wo[2] <= 0.0:
        return wp.vec3(0.0)
    f_i = fresnel_dielectric(wi[2], mat.ior).r
    f_o = fresnel_dielectric(wo[2], mat.ior).r
    denom = wp.vec3(1.0 - mat.fdr_int)
    if mat.nonlinear != 0:
        denom = wp.vec3(1.0) - mat.reflectance * mat.fdr_int
    diff = wp.cw_div(mat.reflectance, denom)
    return diff * (INV_PI * wo[2] * (1.0 - f_i) * (1.0 - f_o) / (mat.ior * mat.ior))


@wp.func
def plastic_pdf(mat: Material, wi: wp.vec3, wo: wp.vec3) -> float:
    if wi[2] <= 0.0 or wo[2] <= 0.0:
        return 0.0
    f_i = fresnel_dielectric(wi[2], mat.ior).r
    return (1.0 - plastic_specular_probability(mat, f_i)) * cosine_hemisphere_pdf(wo)


@wp.func
def plastic_sample(mat: Material, wi: wp.vec3, u_lobe: float, u: wp.vec2) -> BSDFSample:
    s = invalid_sample()
    if wi[2] <= 0.0:
        return s
    f_i = fresnel_dielectric(wi[2], mat.ior).r
    p_spec = plastic_specular_probability(mat, f_i)
    if u_lobe < p_spec:
        return delta_sample(s, reflect_local(wi), p_spec, mat.specular_reflectance * (f_i / p_spec),
                            LOBE_DELTA_REFLECTION)
    s.wo = square_to_cosine_hemisphere(u)
    s.lobe = LOBE_DIFFUSE_REFLECTION
    return s


# ----------------------------------------------------------------------------- rough plastic
@wp.func
def coat_transmittance(mat: Material, cos_t: float) -> float:
    n = mat.coat_transmittance.shape[0]
    x = cos_t * float(n - 1)
    i = wp.min(int(x), n - 2)
    f = x - float(i)
    return mat.coat_transmittance[i] * (1.0 - f) + mat.coat_transmittance[i + 1] * f


@wp.func
def roughplastic_specular_probability(mat: Material, t_i: float) -> float:
    ps = (1.0 - t_i) * mat.specular_sampling_weight
    pd = t_i * (1.0 - mat.specular_sampling_weight)
    return ps / (ps + pd)


@wp.func
def roughplastic_eval_parts(mat: Material, wi: wp.vec3, wo: wp.vec3, lobes: int) -> wp.vec3:
    """The coat's glossy reflection plus the diffuse base, each only where `lobes` has it."""
    if wi[2] <= 0.0 or wo[2] <= 0.0:
        return wp.vec3(0.0)
    out = wp.vec3(0.0)
    if lobes & LOBE_GLOSSY_REFLECTION != 0:
        d = microfacet_of(mat)
        m = wp.normalize(wi + wo)
        spec = fresnel_dielectric(wp.dot(wi, m), mat.ior).r * microfacet_D(d, m) * microfacet_G(d, wi, wo, m) / (4.0 * wi[2])
        out = mat.specular_reflectance * spec
    if lobes & LOBE_DIFFUSE_REFLECTION != 0:
        denom = wp.vec3(1.0 - mat.fdr_int)
        if mat.nonlinear != 0:
            denom = wp.vec3(1.0) - mat.reflectance * mat.fdr_int
        diff = wp.cw_div(mat.reflectance, denom) * (
            INV_PI * wo[2] * coat_transmittance(mat, wi[2]) * coat_transmittance(mat, wo[2]) / (mat.ior * mat.ior))
        out = out + diff
    return out


@wp.func
def roughplastic_eval(mat: Material, wi: wp.vec3, wo: wp.vec3) -> wp.vec3:
    return roughplastic_eval_parts(mat, wi, wo, LOBE_GLOSSY_REFLECTION | LOBE_DIFFUSE_REFLECTION)


@wp.func
def roughplastic_pdf_parts(mat: Material, wi: wp.vec3, wo: wp.vec3, lobes: int) -> float:
    """Density of sampling wo by the lobes in `lobes`, their selection probabilities included."""
    if wi[2] <= 0.0 or wo[2] <= 0.0:
        return 0.0
    p_spec = roughplastic_specular_probability(mat, coat_transmittance(mat, wi[2]))
    out = float(0.0)
    if lobes & LOBE_GLOSSY_REFLECTION != 0:
        m = wp.normalize(wi + wo)
        out = p_spec * (microfacet_pdf(microfacet_of(mat), wi, m) / (4.0 * wp.dot(wo, m)))
    if lobes & LOBE_DIFFUSE_REFLECTION != 0:
        out = out + (1.0 - p_spec) * cosine_hemisphere_pdf(wo)
    return out


@wp.func
def roughplastic_pdf(mat: Material, wi: wp.vec3, wo: wp.vec3) -> float:
    return roughplastic_pdf_parts(mat, wi, wo, LOBE_GLOSSY_REFLECTION | LOBE_DIFFUSE_REFLECTION)


@wp.func
def roughplastic_sample(mat: Material, wi: wp.vec3, u_lobe: float, u: wp.vec2) -> BSDFSample:
    s = invalid_sample()
    if wi[2] <= 0.0:
        return s
    if u_lobe < roughplastic_specular_probability(mat, coat_transmittance(mat, wi[2])):
        s.wo = reflect_about(wi, microfacet_sample(microfacet_of(mat), wi, u))
        s.lobe = LOBE_GLOSSY_REFLECTION
    else:
        s.wo = square_to_cosine_hemisphere(u)
        s.lobe = LOBE_DIFFUSE_REFLECTION
    return s
