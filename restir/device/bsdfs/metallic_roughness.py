"""glTF 2.0's metallic-roughness material (the specification's Appendix B): a diffuse base and a
GGX specular layer with Schlick's Fresnel, blended by `metallic`.

    F      = F0 + (1 - F0) (1 - |wi . h|)^5,  F0 = mix(0.04, base colour, metallic)
    f_diff = (1 - F) c_diff / pi,              c_diff = mix(base colour, 0, metallic)
    f_spec = F D(h) V(wi, wo),                 D: GGX with alpha = roughness^2
    V      = 1 / 2 / (cos_o sqrt(cos_i^2 (1 - a^2) + a^2) + cos_i sqrt(cos_o^2 (1 - a^2) + a^2))

V is the height-correlated Smith visibility G2 / (4 cos_i cos_o) the specification uses. The base
colour is `reflectance`, metallic `metallic`, alpha `alpha_u` (= alpha_v; the loader gives
roughness^2, at least 1e-4 as for every microfacet material here). Two lobes: the specular one is
sampled with probability p_spec (Fresnel at wi's angle against the diffuse albedo left, by
luminance; a function of the material and wi only), by GGX visible normals; the diffuse one by the
cosine. Reflection only, on the front side; `doubleSided` is the dispatcher's twosided.
"""
import warp as wp

from ..color import luminance
from ..microfacet import microfacet_D, microfacet_pdf, microfacet_sample
from ..sampling import cosine_hemisphere_pdf, square_to_cosine_hemisphere
from ..types import INV_PI, LOBE_DIFFUSE_REFLECTION, LOBE_GLOSSY_REFLECTION
from .material import BSDFSample, Material, invalid_sample, microfacet_of, reflect_about

METALLIC_ROUGHNESS_LOBES = LOBE_DIFFUSE_REFLECTION | LOBE_GLOSSY_REFLECTION
DIELECTRIC_F0 = wp.constant(0.04)   # the specification's F0 of non-metals (IOR 1.5)


@wp.func
def schlick(f0: wp.vec3, cos_theta: float) -> wp.vec3:
    c = 1.0 - wp.abs(cos_theta)
    c5 = c * c * c * c * c
    return f0 + (wp.vec3(1.0) - f0) * c5


@wp.func
def mr_f0(mat: Material) -> wp.vec3:
    return wp.vec3(DIELECTRIC_F0) * (1.0 - mat.metallic) + mat.reflectance * mat.metallic


@wp.func
def mr_specular_probability(mat: Material, wi: wp.vec3) -> float:
    f = schlick(mr_f0(mat), wi[2])
    ws = luminance(f)
    wd = luminance(mat.reflectance * (1.0 - mat.metallic)) * (1.0 - ws)
    if ws + wd <= 0.0:
        return 1.0
    return ws / (ws + wd)


@wp.func
def height_correlated_visibility(a2: float, cos_i: float, cos_o: float) -> float:
    gi = cos_o * wp.sqrt(cos_i * cos_i * (1.0 - a2) + a2)
    go = cos_i * wp.sqrt(cos_o * cos_o * (1.0 - a2) + a2)
    return 0.5 / (gi + go)


@wp.func
def metallic_roughness_eval_parts(mat: Material, wi: wp.vec3, wo: wp.vec3, lobes: int) -> wp.vec3:
    """f * cos_o of the lobes in `lobes`."""
    if wi[2] <= 0.0 or wo[2] <= 0.0:
        return wp.vec3(0.0)
    h = wp.normalize(wi + wo)
    F = schlick(mr_f0(mat), wp.dot(wi, h))
    f = wp.vec3(0.0)
    if lobes & LOBE_DIFFUSE_REFLECTION != 0:
        c_diff = mat.reflectance * (1.0 - mat.metallic)
        f = f + wp.cw_mul(wp.vec3(1.0) - F, c_diff) * (INV_PI * wo[2])
    if lobes & LOBE_GLOSSY_REFLECTION != 0:
        a2 = mat.alpha_u * mat.alpha_u
        f = f + F * (microfacet_D(microfacet_of(mat), h) * height_correlated_visibility(a2, wi[2], wo[2]) * wo[2])
    return f


@wp.func
def metallic_roughness_pdf_parts(mat: Material, wi: wp.vec3, wo: wp.vec3, lobes: int) -> float:
    """The density of choosing a lobe in `lobes` and sampling wo in it."""
    if wi[2] <= 0.0 or wo[2] <= 0.0:
        return 0.0
    ps = mr_specular_probability(mat, wi)
    p = 0.0
    if lobes & LOBE_DIFFUSE_REFLECTION != 0:
        p = p + (1.0 - ps) * cosine_hemisphere_pdf(wo)
    if lobes & LOBE_GLOSSY_REFLECTION != 0:
        h = wp.normalize(wi + wo)
        p = p + ps * microfacet_pdf(microfacet_of(mat), wi, h) / (4.0 * wp.dot(wo, h))
    return p


@wp.func
def metallic_roughness_eval(mat: Material, wi: wp.vec3, wo: wp.vec3) -> wp.vec3:
    return metallic_roughness_eval_parts(mat, wi, wo, METALLIC_ROUGHNESS_LOBES)


@wp.func
def metallic_roughness_pdf(mat: Material, wi: wp.vec3, wo: wp.vec3) -> float:
    return metallic_roughness_pdf_parts(mat, wi, wo, METALLIC_ROUGHNESS_LOBES)


@wp.func
def metallic_roughness_sample(mat: Material, wi: wp.vec3, u_lobe: float, u: wp.vec2) -> BSDFSample:
    s = invalid_sample()
    if wi[2] <= 0.0:
        return s
    if u_lobe < mr_specular_probability(mat, wi):
        s.wo = reflect_about(wi, microfacet_sample(microfacet_of(mat), wi, u))
        s.lobe = LOBE_GLOSSY_REFLECTION
    else:
        s.wo = square_to_cosine_hemisphere(u)
        s.lobe = LOBE_DIFFUSE_REFLECTION
    return s
