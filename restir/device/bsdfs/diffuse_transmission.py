"""pbrt-v4's `diffusetransmission`: Lambertian reflection (albedo R = `reflectance`) on the side of
wi and Lambertian transmission (T = `specular_transmittance`) to the other side, with no
refraction:

    f(wi, wo) = R / pi  (wo on wi's side),  T / pi  (wo on the other side)

Each side is chosen with probability proportional to the largest component of its albedo, as
pbrt-v4 chooses, then the direction by the cosine. The material is the same from both sides (the
loader makes it two-sided, so the kind sees wi on its front).
"""
import warp as wp

from ..color import max3
from ..sampling import cosine_hemisphere_pdf, square_to_cosine_hemisphere
from ..types import INV_PI, LOBE_DIFFUSE_REFLECTION, LOBE_DIFFUSE_TRANSMISSION
from .material import BSDFSample, Material, flip_z, invalid_sample

DIFFUSE_TRANSMISSION_LOBES = LOBE_DIFFUSE_REFLECTION | LOBE_DIFFUSE_TRANSMISSION


@wp.func
def reflection_probability(mat: Material) -> float:
    pr = max3(mat.reflectance)
    pt = max3(mat.specular_transmittance)
    if pr + pt <= 0.0:
        return 1.0
    return pr / (pr + pt)


@wp.func
def diffuse_transmission_eval(mat: Material, wi: wp.vec3, wo: wp.vec3) -> wp.vec3:
    if wi[2] <= 0.0 or wo[2] == 0.0:
        return wp.vec3(0.0)
    if wo[2] > 0.0:
        return mat.reflectance * (INV_PI * wo[2])
    return mat.specular_transmittance * (INV_PI * -wo[2])


@wp.func
def diffuse_transmission_pdf(mat: Material, wi: wp.vec3, wo: wp.vec3) -> float:
    if wi[2] <= 0.0 or wo[2] == 0.0:
        return 0.0
    pr = reflection_probability(mat)
    if wo[2] > 0.0:
        return pr * cosine_hemisphere_pdf(wo)
    return (1.0 - pr) * cosine_hemisphere_pdf(flip_z(wo))


@wp.func
def diffuse_transmission_sample(mat: Material, wi: wp.vec3, u_lobe: float, u: wp.vec2) -> BSDFSample:
    s = invalid_sample()
    if wi[2] <= 0.0:
        return s
    d = square_to_cosine_hemisphere(u)
    if u_lobe < reflection_probability(mat):
        s.wo = d
        s.lobe = LOBE_DIFFUSE_REFLECTION
    else:
        s.wo = flip_z(d)
        s.lobe = LOBE_DIFFUSE_TRANSMISSION
    return s
