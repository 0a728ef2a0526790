"""Lambertian reflection (Mitsuba's `diffuse`): one diffuse lobe, cosine-weighted sampling."""
import warp as wp

from ..sampling import cosine_hemisphere_pdf, square_to_cosine_hemisphere
from ..types import INV_PI, LOBE_DIFFUSE_REFLECTION
from .material import BSDFSample, Material, invalid_sample

DIFFUSE_LOBES = LOBE_DIFFUSE_REFLECTION


@wp.func
def diffuse_eval(mat: Material, wi: wp.vec3, wo: wp.vec3) -> wp.vec3:
    if wi[2] <= 0.0 or wo[2] <= 0.0:
        return wp.vec3(0.0)
    return mat.reflectance * (INV_PI * wo[2])


@wp.func
def diffuse_pdf(mat: Material, wi: wp.vec3, wo: wp.vec3) -> float:
    if wi[2] <= 0.0:
        return 0.0
    return cosine_hemisphere_pdf(wo)


@wp.func
def diffuse_sample(mat: Material, wi: wp.vec3, u_lobe: float, u: wp.vec2) -> BSDFSample:
    s = invalid_sample()
    if wi[2] <= 0.0:
        return s
    s.wo = square_to_cosine_hemisphere(u)
    s.lobe = LOBE_DIFFUSE_REFLECTION
    return s
