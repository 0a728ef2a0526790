"""BSDFs: the dispatch over material kinds, with explicit random numbers, in the local shading frame.

Each kind's eval, pdf, sample and lobes live together in `device/bsdfs/` (one module per kind);
this module picks the kind, mirrors two-sided materials hit from the back, and holds what path
reuse asks of lobes. Conventions (Mitsuba's): `wi` points toward the previous vertex (the camera
side), `wo` is the scattered direction, both away from the surface; `bsdf_eval` returns
f(wi, wo) * |cos theta_o|; `BSDFSample.weight` = eval / pdf. Delta lobes have eval = pdf = 0 and
`is_delta` set. Radiance is scaled by 1/eta^2 on refraction (radiance transport, as Mitsuba).
A bump-mapped material (device/bump.py) is evaluated in its tilted frame, which the caller's
vectors are in, and eval takes the bump map's factor here, after the kind's value. A masked one
(Mitsuba 3's `mask`) is the blend opacity * (the kind) + (1 - opacity) * (the null lobe, straight
through): eval and pdf take the factor opacity here, and `bsdf_sample` picks the null lobe.

Adding a material kind: a module in bsdfs/ with its eval, pdf, sample and LOBES, its line in
bsdfs/registry.py, and the branches that table asks for here (`kind_eval`, `kind_pdf`,
`kind_sample`, `kind_lobes`, and `smooth_lobe` or the `*_parts` calls of `bsdf_eval_lobes` and
`bsdf_pdf_lobes`; tests/unit/test_bsdf_registry.py checks them); its MAT_* constant in types.py,
and its parameters in the loader (scene.py; a spectrum read with `spectrum()` is texturable with
no device change).

Lobes (types.py LOBE_*): every sample reports the lobe it chose; `bsdf_eval_lobes` and
`bsdf_pdf_lobes` restrict eval and pdf to a mask of lobes (the pdf including the probability of
choosing those lobes, so restricted pdfs over a partition of the lobes sum to `bsdf_pdf`).
`lobe_is_rough` and `bsdf_has_rough_component` classify lobes for path reuse: a reconnection
needs rough lobes at both ends (docs/theory/restir_pt.md#the-lobe-separated-path-bsdf and
#the-reconnection-vertex).
"""
import warp as wp

from .bsdfs.conductor import CONDUCTOR_LOBES, ROUGHCONDUCTOR_LOBES, conductor_sample, roughconductor_eval, roughconductor_pdf, roughconductor_sample
from .bsdfs.dielectric import (DIELECTRIC_LOBES, ROUGHDIELECTRIC_LOBES, dielectric_sample, roughdielectric_eval,
                               roughdielectric_pdf, roughdielectric_sample, thindielectric_sample)
from .bsdfs.diffuse import DIFFUSE_LOBES, diffuse_eval, diffuse_pdf, diffuse_sample
from .bsdfs.diffuse_transmission import (DIFFUSE_TRANSMISSION_LOBES, diffuse_transmission_eval, diffuse_transmission_pdf,
                                         diffuse_transmission_sample)
from .bsdfs.metallic_roughness import (METALLIC_ROUGHNESS_LOBES, metallic_roughness_eval, metallic_roughness_eval_parts,
                                       metallic_roughness_pdf, metallic_roughness_pdf_parts, metallic_roughness_sample)
from .bsdfs.material import BSDFSample, Material, flip_z, invalid_sample, null_sample  # noqa: F401  (the BSDF interface)
from .bsdfs.plastic import (PLASTIC_LOBES, ROUGHPLASTIC_LOBES, plastic_eval, plastic_pdf, plastic_sample,
                            roughplastic_eval, roughplastic_pdf, roughplastic_pdf_parts, roughplastic_eval_parts,
                            roughplastic_sample)
from .bump import bump_factor
from .types import (
    LOBE_DIFFUSE_REFLECTION,
    LOBE_DIFFUSE_TRANSMISSION,
    LOBE_GLOSSY_REFLECTION,
    LOBE_GLOSSY_TRANSMISSION,
    LOBE_NULL,
    LOBES_DELTA,
    LOBES_DIFFUSE,
    LOBES_GLOSSY,
    MAT_CONDUCTOR,
    MAT_DIELECTRIC,
    MAT_DIFFUSE,
    MAT_DIFFUSE_TRANSMISSION,
    MAT_METALLIC_ROUGHNESS,
    MAT_PLASTIC,
    MAT_ROUGHCONDUCTOR,
    MAT_ROUGHPLASTIC,
    MAT_ROUGHDIELECTRIC,
    MAT_THINDIELECTRIC,
)


@wp.func
def to_front(mat: Material, wi: wp.vec3, v: wp.vec3) -> wp.vec3:
    """v as the front side sees it: a two-sided material hit from the back (wi below the
    surface) behaves as its front, so both directions are mirrored through the surface.
    (kind_eval and kind_pdf spell this out inline: through this function, twice per call, the
    path tracer ran about 5% slower on the CPU.)"""
    if mat.twosided != 0 and wi[2] < 0.0:
        return flip_z(v)
    return v


# ----------------------------------------------------------------------------- dispatch
# bsdf_eval, bsdf_pdf, bsdf_sample and their lobe-restricted forms are out of line (CUDA
# __noinline__): each holds every material kind, and a ReSTIR kernel calls them from tens of
# places (base path, both shift directions, replay, reconnection); inlined, the CUDA build of the
# ReSTIR PT module took 171 s and Suffix ReSTIR's 295 s, out of line 42 s and 83 s (sm_90, 2 busy
# cores). On the CPU the calls cost 1-2% of a frame (same-run A/B: pt 1.009, restir-pt 1.015,
# suffix-restir 1.019).
@wp.func
def kind_eval(mat: Material, wi_in: wp.vec3, wo_in: wp.vec3) -> wp.vec3:
    """The kind's f * |cos|, a two-sided material hit from the back mirrored to its front. Each
    branch returns (see kind_sample)."""
    wi = wi_in
    wo = wo_in
    if mat.twosided != 0 and wi[2] < 0.0:
        wi = flip_z(wi)
        wo = flip_z(wo)
    if mat.kind == MAT_DIFFUSE:
        return diffuse_eval(mat, wi, wo)
    if mat.kind == MAT_ROUGHCONDUCTOR:
        return roughconductor_eval(mat, wi, wo)
    if mat.kind == MAT_ROUGHDIELECTRIC:
        return roughdielectric_eval(mat, wi, wo)
    if mat.kind == MAT_PLASTIC:
        return plastic_eval(mat, wi, wo)
    if mat.kind == MAT_ROUGHPLASTIC:
        return roughplastic_eval(mat, wi, wo)
    if mat.kind == MAT_METALLIC_ROUGHNESS:
        return metallic_roughness_eval(mat, wi, wo)
    if mat.kind == MAT_DIFFUSE_TRANSMISSION:
        return diffuse_transmission_eval(mat, wi, wo)
    return wp.vec3(0.0)  # delta-only kinds


@wp.func
def kind_pdf(mat: Material, wi_in: wp.vec3, wo_in: wp.vec3) -> float:
    wi = wi_in
    wo = wo_in
    if mat.twosided != 0 and wi[2] < 0.0:
        wi = flip_z(wi)
        wo = flip_z(wo)
    if mat.kind == MAT_DIFFUSE:
        return diffuse_pdf(mat, wi, wo)
    if mat.kind == MAT_ROUGHCONDUCTOR:
        return roughconductor_pdf(mat, wi, wo)
    if mat.kind == MAT_ROUGHDIELECTRIC:
        return roughdielectric_pdf(mat, wi, wo)
    if mat.kind == MAT_PLASTIC:
        return plastic_pdf(mat, wi, wo)
    if mat.kind == MAT_ROUGHPLASTIC:
        return roughplastic_pdf(mat, wi, wo)
    if mat.kind == MAT_METALLIC_ROUGHNESS:
        return metallic_roughness_pdf(mat, wi, wo)
    if mat.kind == MAT_DIFFUSE_TRANSMISSION:
        return diffuse_transmission_pdf(mat, wi, wo)
    return 0.0  # delta-only kinds


@wp.func(inline=False)
def bsdf_eval(mat: Material, wi: wp.vec3, wo: wp.vec3) -> wp.vec3:
    f = kind_eval(mat, wi, wo) * mat.opacity
    if mat.bumped != 0:
        f = f * bump_factor(mat.bump_n0, mat.bump_alpha2, wo)
    return f


@wp.func(inline=False)
def bsdf_pdf(mat: Material, wi: wp.vec3, wo: wp.vec3) -> float:
    p = kind_pdf(mat, wi, wo) * mat.opacity
    if mat.bumped != 0:
        if bump_factor(mat.bump_n0, 0.0, wo) == 0.0:
            p = 0.0
    return p


@wp.func
def kind_sample(mat: Material, wi: wp.vec3, u_lobe: float, u: wp.vec2) -> BSDFSample:
    """The sample of the material's kind. Each branch returns: a sample assigned in an if / elif
    chain is merged by Warp through a select of the whole struct per branch, eight nested copies,
    and the path tracer's CPU frame took 7-10% longer (same-run A/B,
    docs/changelog.md#speed-one-bsdf-module-per-kind)."""
    if mat.kind == MAT_DIFFUSE:
        return diffuse_sample(mat, wi, u_lobe, u)
    if mat.kind == MAT_CONDUCTOR:
        return conductor_sample(mat, wi, u_lobe, u)
    if mat.kind == MAT_ROUGHCONDUCTOR:
        return roughconductor_sample(mat, wi, u_lobe, u)
    if mat.kind == MAT_DIELECTRIC:
        return dielectric_sample(mat, wi, u_lobe, u)
    if mat.kind == MAT_THINDIELECTRIC:
        return thindielectric_sample(mat, wi, u_lobe, u)
    if mat.kind == MAT_ROUGHDIELECTRIC:
        return roughdielectric_sample(mat, wi, u_lobe, u)
    if mat.kind == MAT_PLASTIC:
        return plastic_sample(mat, wi, u_lobe, u)
    if mat.kind == MAT_ROUGHPLASTIC:
        return roughplastic_sample(mat, wi, u_lobe, u)
    if mat.kind == MAT_METALLIC_ROUGHNESS:
        return metallic_roughness_sample(mat, wi, u_lobe, u)
    if mat.kind == MAT_DIFFUSE_TRANSMISSION:
        return diffuse_transmission_sample(mat, wi, u_lobe, u)
    return invalid_sample()


@wp.func(inline=False)
def bsdf_sample(mat: Material, wi_in: wp.vec3, u_lobe: float, u: wp.vec2) -> BSDFSample:
    """A direction from the material's lobes: u_lobe picks the lobe, u the direction in it.

    A kind's sample function picks the direction and the lobe; for a delta lobe it also sets the
    pdf and weight. Every non-delta sample is weighted here, by `bsdf_pdf` and `bsdf_eval`: the
    same functions NEE and MIS use, so a sample's weight is eval / pdf by construction and one
    out-of-line call of each serves every kind. A mask passes through when u_lobe >= opacity and
    otherwise hands the kind u_lobe / opacity (Mitsuba's order; for opacity 1 both are exact
    no-ops)."""
    if u_lobe >= mat.opacity:
        return null_sample(wi_in, 1.0 - mat.opacity)
    wi = wi_in
    flipped = mat.twosided != 0 and wi[2] < 0.0
    if flipped:
        wi = flip_z(wi)
    s = kind_sample(mat, wi, u_lobe / mat.opacity, u)
    if flipped:
        s.wo = flip_z(s.wo)  # back in the caller's frame, where bsdf_pdf and bsdf_eval take it
    if s.lobe != 0 and s.is_delta == 0:
        # Directions on the wrong side (or where the lobe is zero) have pdf or eval 0: invalid.
        s.pdf = bsdf_pdf(mat, wi_in, s.wo)
        if s.pdf > 0.0:
            f = bsdf_eval(mat, wi_in, s.wo)
            if f[0] > 0.0 or f[1] > 0.0 or f[2] > 0.0:
                s.weight = f / s.pdf
                s.valid = 1
    else:
        s.pdf = s.pdf * mat.opacity  # a delta lobe's probability of being chosen, the mask's included
        if s.valid != 0 and mat.bumped != 0:
            # a delta lobe's weight takes the bump map's factor as eval does (Mitsuba's bumpmap sample)
            b = bump_factor(mat.bump_n0, mat.bump_alpha2, s.wo)
            s.weight = s.weight * b
            if b <= 0.0:
                s.valid = 0
    if s.valid == 0:
        s.lobe = 0
    return s


@wp.func
def bsdf_lobes(mat: Material) -> int:
    """The lobes (LOBE_* mask) the material has: its kind's, and a mask's null lobe."""
    return kind_lobes(mat) | wp.where(mat.masked != 0, LOBE_NULL, 0)


@wp.func
def kind_lobes(mat: Material) -> int:
    if mat.kind == MAT_DIFFUSE:
        return DIFFUSE_LOBES
    if mat.kind == MAT_CONDUCTOR:
        return CONDUCTOR_LOBES
    if mat.kind == MAT_ROUGHCONDUCTOR:
        return ROUGHCONDUCTOR_LOBES
    if mat.kind == MAT_DIELECTRIC or mat.kind == MAT_THINDIELECTRIC:
        return DIELECTRIC_LOBES
    if mat.kind == MAT_ROUGHDIELECTRIC:
        return ROUGHDIELECTRIC_LOBES
    if mat.kind == MAT_PLASTIC:
        return PLASTIC_LOBES
    if mat.kind == MAT_ROUGHPLASTIC:
        return ROUGHPLASTIC_LOBES
    if mat.kind == MAT_METALLIC_ROUGHNESS:
        return METALLIC_ROUGHNESS_LOBES
    if mat.kind == MAT_DIFFUSE_TRANSMISSION:
        return DIFFUSE_TRANSMISSION_LOBES
    return 0


@wp.func
def bsdf_is_delta_only(mat: Material) -> int:
    if bsdf_lobes(mat) & (LOBES_DIFFUSE | LOBES_GLOSSY) == 0:
        return 1
    return 0


# ----------------------------------------------------------------------------- lobes
@wp.func
def smooth_lobe(mat: Material, wi: wp.vec3, wo: wp.vec3) -> int:
    """The one non-delta lobe that can scatter wi into wo, for materials with at most one such
    lobe on each side (all but those with `parts` in bsdfs/registry.py); 0 for delta-only
    materials."""
    if mat.kind == MAT_DIFFUSE or mat.kind == MAT_PLASTIC:
        return LOBE_DIFFUSE_REFLECTION
    if mat.kind == MAT_ROUGHCONDUCTOR:
        return LOBE_GLOSSY_REFLECTION
    if mat.kind == MAT_ROUGHDIELECTRIC:
        return wp.where(wi[2] * wo[2] > 0.0, LOBE_GLOSSY_REFLECTION, LOBE_GLOSSY_TRANSMISSION)
    if mat.kind == MAT_DIFFUSE_TRANSMISSION:
        return wp.where(wi[2] * wo[2] > 0.0, LOBE_DIFFUSE_REFLECTION, LOBE_DIFFUSE_TRANSMISSION)
    return 0


@wp.func
def has_lobe_parts(mat: Material) -> bool:
    """The material has several non-delta lobes on a side (`parts` in bsdfs/registry.py): its
    lobe-restricted eval and pdf differ from the full ones."""
    return mat.kind == MAT_ROUGHPLASTIC or mat.kind == MAT_METALLIC_ROUGHNESS


@wp.func
def kind_eval_parts(mat: Material, wi: wp.vec3, wo: wp.vec3, lobes: int, wo_in: wp.vec3) -> wp.vec3:
    """A `parts` kind's eval restricted to `lobes` (wi, wo on its front), with the mask's and the
    bump map's factors (wo_in: wo in the caller's frame). Each branch returns (see kind_sample)."""
    if mat.kind == MAT_ROUGHPLASTIC:
        return roughplastic_eval_parts(mat, wi, wo, lobes) * mat.opacity * lobe_bump(mat, wo_in)
    return metallic_roughness_eval_parts(mat, wi, wo, lobes) * mat.opacity * lobe_bump(mat, wo_in)


@wp.func
def kind_pdf_parts(mat: Material, wi: wp.vec3, wo: wp.vec3, lobes: int) -> float:
    if mat.kind == MAT_ROUGHPLASTIC:
        return roughplastic_pdf_parts(mat, wi, wo, lobes)
    return metallic_roughness_pdf_parts(mat, wi, wo, lobes)


@wp.func
def lobe_bump(mat: Material, wo_in: wp.vec3) -> float:
    if mat.bumped != 0:
        return bump_factor(mat.bump_n0, mat.bump_alpha2, wo_in)
    return 1.0


@wp.func(inline=False)
def bsdf_eval_lobes(mat: Material, wi_in: wp.vec3, wo_in: wp.vec3, lobes: int) -> wp.vec3:
    """bsdf_eval restricted to the lobes in the mask `lobes` (delta lobes evaluate to 0 anyway)."""
    if has_lobe_parts(mat):
        return kind_eval_parts(mat, to_front(mat, wi_in, wi_in), to_front(mat, wi_in, wo_in), lobes, wo_in)
    if smooth_lobe(mat, wi_in, wo_in) & lobes == 0:
        return wp.vec3(0.0)
    return bsdf_eval(mat, wi_in, wo_in)


@wp.func(inline=False)
def bsdf_pdf_lobes(mat: Material, wi_in: wp.vec3, wo_in: wp.vec3, lobes: int) -> float:
    """bsdf_pdf restricted to the lobes in `lobes`: the density of choosing one of them and then
    sampling wo (the single-lobe pdf of ReSTIR PT's lobe-separated path BSDF)."""
    if has_lobe_parts(mat):
        p = kind_pdf_parts(mat, to_front(mat, wi_in, wi_in), to_front(mat, wi_in, wo_in), lobes) * mat.opacity
        if mat.bumped != 0:
            if bump_factor(mat.bump_n0, 0.0, wo_in) == 0.0:
                p = 0.0
        return p
    if smooth_lobe(mat, wi_in, wo_in) & lobes == 0:
        return 0.0
    return bsdf_pdf(mat, wi_in, wo_in)


@wp.func
def linear_roughness(mat: Material) -> float:
    """Roughness on the linear scale (microfacet alpha = roughness^2, the convention of Falcor's
    thresholds); for anisotropic lobes the smoother direction's, so "rough" means rough everywhere."""
    return wp.sqrt(wp.min(mat.alpha_u, mat.alpha_v))


@wp.func
def lobe_is_rough(mat: Material, lobe: int, threshold: float) -> bool:
    """Diffuse lobes are rough; glossy lobes when their linear roughness exceeds `threshold`
    (ReSTIR PT: 0.2); delta lobes never."""
    if lobe & LOBES_DIFFUSE != 0:
        return True
    if lobe & LOBES_DELTA != 0 or lobe == 0:
        return False
    return linear_roughness(mat) > threshold


@wp.func
def bsdf_has_rough_component(mat: Material, threshold: float) -> bool:
    """True when some lobe of the material is rough (a diffuse part, or a glossy lobe rougher than
    `threshold`): the condition for a vertex to serve as a reconnection vertex."""
    lobes = bsdf_lobes(mat)
    if lobes & LOBES_DIFFUSE != 0:
        return True
    if lobes & LOBES_GLOSSY != 0:
        return linear_roughness(mat) > threshold
    return False
