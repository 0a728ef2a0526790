"""The material record every BSDF reads, the sample every BSDF returns, and their helpers.

Conventions (Mitsuba's): `wi` points toward the previous vertex (the camera side), `wo` is the
scattered direction, both away from the surface; eval returns f(wi, wo) * |cos theta_o|;
`BSDFSample.weight` = eval / pdf. Delta lobes have eval = pdf = 0 and `is_delta` set.
"""
import warp as wp

from ..microfacet import Microfacet
from ..types import LOBE_NULL


@wp.struct
class Material:
    kind: int
    twosided: int              # 1: the back side behaves as the front (Mitsuba `twosided`)
    # Texturable (scene.py TEXTURED_PARAMETERS): a textured one is overwritten at each hit by
    # scene_device.textured_material before any BSDF reads it; the texture indices live beside the
    # materials (SceneDevice.material_textures), not in this record, which is copied by value.
    reflectance: wp.vec3       # diffuse albedo
    specular_reflectance: wp.vec3
    specular_transmittance: wp.vec3
    eta: wp.vec3               # conductor: real part of the complex IOR
    k: wp.vec3                 # conductor: imaginary part
    ior: float                 # dielectrics: interior / exterior IOR
    distribution: int          # MICROFACET_*
    alpha_u: float
    alpha_v: float
    # plastic / roughplastic: a dielectric coat (ior; rough: distribution, alpha_u) over a diffuse
    # base (reflectance)
    specular_sampling_weight: float
    fdr_int: float             # reflectance of the coat for diffuse light from inside
    nonlinear: int
    coat_transmittance: wp.array(dtype=float)  # roughplastic: T(cos) at cos = i/63 (scene/coat_tables.py)
    # A bump map (device/bump.py): `bumped` is set in the scene's record of a bump-mapped material,
    # the other two per hit by bounce.material_at; bsdf.py multiplies eval by bump.bump_factor.
    bumped: int
    bump_n0: wp.vec3           # the unperturbed shading normal ns in the tilted frame
    bump_alpha2: float         # the terminator-shadowing alpha^2 (0: no shadowing)
    # A mask (Mitsuba 3's `mask`): with probability 1 - opacity the path passes straight through
    # (the null lobe), else the material scatters, so eval and pdf carry the factor opacity.
    # `masked` is set in the scene's record and decides the lobe set (never a hit's value);
    # `opacity` is 1 on unmasked materials (every product with it is then exact) and, where a
    # texture drives it, resolved per hit by scene_device.textured_material.
    masked: int
    opacity: float
    # A textured roughness (scene_device.textured_material): ROUGHNESS_IS_ALPHA (Mitsuba 3's
    # textured alpha), ROUGHNESS_SQRT (pbrt-v4's roughness, alpha = sqrt) or ROUGHNESS_SQUARED
    # (glTF's, alpha = roughness^2)
    roughness_remap: int
    metallic: float            # glTF's metallic-roughness: the metal fraction (textured: per hit)


@wp.struct
class BSDFSample:
    wo: wp.vec3
    weight: wp.vec3   # f * |cos| / pdf
    pdf: float        # solid-angle density (the lobe-selection probability included)
    is_delta: int
    eta: float        # relative IOR crossed (1 for reflection)
    valid: int
    lobe: int         # the LOBE_* flag of the lobe sampled (0 when invalid)


@wp.func
def invalid_sample() -> BSDFSample:
    s = BSDFSample()
    s.wo = wp.vec3(0.0, 0.0, 1.0)
    s.weight = wp.vec3(0.0, 0.0, 0.0)
    s.pdf = 0.0
    s.is_delta = 0
    s.eta = 1.0
    s.valid = 0
    s.lobe = 0
    return s


@wp.func
def delta_sample(s_in: BSDFSample, wo: wp.vec3, pdf: float, weight: wp.vec3, lobe: int) -> BSDFSample:
    """A sample of a delta lobe: its probability of being chosen and its weight are given."""
    s = s_in
    s.wo = wo
    s.pdf = pdf
    s.weight = weight
    s.is_delta = 1
    s.valid = 1
    s.lobe = lobe
    return s


@wp.func
def null_sample(wi: wp.vec3, pdf: float) -> BSDFSample:
    """A mask's pass-through: wo = -wi (no change of direction or medium), chosen with
    probability pdf = 1 - opacity, weight 1 (Mitsuba's mask sample)."""
    s = invalid_sample()
    s.wo = -wi
    s.pdf = pdf
    s.weight = wp.vec3(1.0)
    s.is_delta = 1
    s.valid = 1
    s.lobe = LOBE_NULL
    return s


@wp.func
def microfacet_of(mat: Material) -> Microfacet:
    d = Microfacet()
    d.kind = mat.distribution
    d.alpha_u = mat.alpha_u
    d.alpha_v = mat.alpha_v
    return d


@wp.func
def reflect_local(wi: wp.vec3) -> wp.vec3:
    return wp.vec3(-wi[0], -wi[1], wi[2])


@wp.func
def reflect_about(wi: wp.vec3, m: wp.vec3) -> wp.vec3:
    return 2.0 * wp.dot(wi, m) * m - wi


@wp.func
def flip_z(v: wp.vec3) -> wp.vec3:
    return wp.vec3(v[0], v[1], -v[2])
