"""BSDFs: eval / pdf / sample with explicit random numbers, in the local shading frame.

Conventions (Mitsuba's): `wi` points toward the previous vertex (the camera side), `wo` is the
scattered direction, both away from the surface; `bsdf_eval` returns f(wi, wo) * |cos theta_o|;
`BSDFSample.weight` = eval / pdf. Delta lobes have eval = pdf = 0 and `is_delta` set.
Radiance is scaled by 1/eta^2 on refraction (radiance transport, as Mitsuba).

Lobes (types.py LOBE_*): every sample reports the lobe it chose; `bsdf_eval_lobes` and
`bsdf_pdf_lobes` restrict eval and pdf to a mask of lobes (the pdf including the probability of
choosing those lobes, so restricted pdfs over a partition of the lobes sum to `bsdf_pdf`).
`lobe_is_rough` and `bsdf_has_rough_component` classify lobes for path reuse: a reconnection
needs rough lobes at both ends (ALGORITHMS.md 2.4, 3.1).
"""
import warp as wp

from .fresnel import fresnel_conductor, fresnel_dielectric
from .microfacet import Microfacet, microfacet_D, microfacet_G, microfacet_pdf, microfacet_sample
from .sampling import cosine_hemisphere_pdf, square_to_cosine_hemisphere
from .types import (
    INV_PI,
    LOBE_DELTA_REFLECTION,
    LOBE_DELTA_TRANSMISSION,
    LOBE_DIFFUSE_REFLECTION,
    LOBE_GLOSSY_REFLECTION,
    LOBE_GLOSSY_TRANSMISSION,
    LOBES_DELTA,
    LOBES_DIFFUSE,
    MAT_CONDUCTOR,
    MAT_DIELECTRIC,
    MAT_DIFFUSE,
    MAT_PLASTIC,
    MAT_ROUGHCONDUCTOR,
    MAT_ROUGHPLASTIC,
    MAT_ROUGHDIELECTRIC,
    MAT_THINDIELECTRIC,
)


@wp.struct
class Material:
    kind: int
    twosided: int              # 1: the back side behaves as the front (Mitsuba `twosided`)
    reflectance: wp.vec3       # diffuse albedo
    reflectance_tex: int       # texture index or -1
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
def microfacet_of(mat: Material) -> Microfacet:
    d = Microfacet()
    d.kind = mat.distribution
    d.alpha_u = mat.alpha_u
    d.alpha_v = mat.alpha_v
    return d


@wp.func
def bsdf_is_delta_only(mat: Material) -> int:
    if mat.kind == MAT_CONDUCTOR or mat.kind == MAT_DIELECTRIC or mat.kind == MAT_THINDIELECTRIC:
        return 1
    return 0


@wp.func
def reflect_local(wi: wp.vec3) -> wp.vec3:
    return wp.vec3(-wi[0], -wi[1], wi[2])


@wp.func
def reflect_about(wi: wp.vec3, m: wp.vec3) -> wp.vec3:
    return 2.0 * wp.dot(wi, m) * m - wi


@wp.func
def flip_z(v: wp.vec3) -> wp.vec3:
    return wp.vec3(v[0], v[1], -v[2])


@wp.func
def to_front(mat: Material, wi: wp.vec3, v: wp.vec3) -> wp.vec3:
    """v as the front side sees it: a two-sided material hit from the back (wi below the
    surface) behaves as its front, so both directions are mirrored through the surface.
    (bsdf_eval and bsdf_pdf spell this out inline: through this function, twice per call, the
    path tracer ran about 5% slower on the CPU.)"""
    if mat.twosided != 0 and wi[2] < 0.0:
        return flip_z(v)
    return v


# ----------------------------------------------------------------------------- rough dielectric helpers
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


# ----------------------------------------------------------------------------- plastic (Mitsuba's model)
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


# ----------------------------------------------------------------------------- rough plastic (Mitsuba's model)
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


# ----------------------------------------------------------------------------- dispatch
# bsdf_eval, bsdf_pdf, bsdf_sample and their lobe-restricted forms are out of line (CUDA
# __noinline__): each holds every material kind, and a ReSTIR kernel calls them from tens of
# places (base path, both shift directions, replay, reconnection); inlined, the CUDA build of the
# ReSTIR PT module took 171 s and Suffix ReSTIR's 295 s, out of line 42 s and 83 s (sm_90, 2 busy
# cores). On the CPU the calls cost 1-2% of a frame (same-run A/B: pt 1.009, restir-pt 1.015,
# suffix-restir 1.019).
@wp.func(inline=False)
def bsdf_eval(mat: Material, wi_in: wp.vec3, wo_in: wp.vec3) -> wp.vec3:
    wi = wi_in
    wo = wo_in
    if mat.twosided != 0 and wi[2] < 0.0:
        wi = flip_z(wi)
        wo = flip_z(wo)
    if mat.kind == MAT_DIFFUSE:
        if wi[2] <= 0.0 or wo[2] <= 0.0:
            return wp.vec3(0.0)
        return mat.reflectance * (INV_PI * wo[2])
    if mat.kind == MAT_ROUGHCONDUCTOR:
        if wi[2] <= 0.0 or wo[2] <= 0.0:
            return wp.vec3(0.0)
        m = wp.normalize(wi + wo)
        d = microfacet_of(mat)
        v = microfacet_D(d, m) * microfacet_G(d, wi, wo, m) / (4.0 * wi[2])
        F = fresnel_conductor(wp.dot(wi, m), mat.eta, mat.k)
        return wp.cw_mul(F, mat.specular_reflectance) * v
    if mat.kind == MAT_ROUGHDIELECTRIC:
        return roughdielectric_eval(mat, wi, wo)
    if mat.kind == MAT_PLASTIC:
        return plastic_eval(mat, wi, wo)
    if mat.kind == MAT_ROUGHPLASTIC:
        return roughplastic_eval(mat, wi, wo)
    return wp.vec3(0.0)


@wp.func(inline=False)
def bsdf_pdf(mat: Material, wi_in: wp.vec3, wo_in: wp.vec3) -> float:
    wi = wi_in
    wo = wo_in
    if mat.twosided != 0 and wi[2] < 0.0:
        wi = flip_z(wi)
        wo = flip_z(wo)
    if mat.kind == MAT_DIFFUSE:
        if wi[2] <= 0.0:
            return 0.0
        return cosine_hemisphere_pdf(wo)
    if mat.kind == MAT_ROUGHCONDUCTOR:
        if wi[2] <= 0.0 or wo[2] <= 0.0:
            return 0.0
        m = wp.normalize(wi + wo)
        d = microfacet_of(mat)
        return microfacet_pdf(d, wi, m) / (4.0 * wp.dot(wo, m))
    if mat.kind == MAT_ROUGHDIELECTRIC:
        return roughdielectric_pdf(mat, wi, wo)
    if mat.kind == MAT_PLASTIC:
        return plastic_pdf(mat, wi, wo)
    if mat.kind == MAT_ROUGHPLASTIC:
        return roughplastic_pdf(mat, wi, wo)
    return 0.0


@wp.func(inline=False)
def bsdf_sample(mat: Material, wi_in: wp.vec3, u_lobe: float, u: wp.vec2) -> BSDFSample:
    wi = wi_in
    flipped = mat.twosided != 0 and wi[2] < 0.0
    if flipped:
        wi = flip_z(wi)
    s = invalid_sample()
    # Each kind picks a direction; delta lobes also set pdf and weight. Every other sample is
    # weighted below by the same eval and pdf functions that NEE and MIS use.
    evaluate = int(0)
    if mat.kind == MAT_DIFFUSE:
        if wi[2] <= 0.0:
            return s
        s.wo = square_to_cosine_hemisphere(u)
        s.lobe = LOBE_DIFFUSE_REFLECTION
        evaluate = 1
    elif mat.kind == MAT_CONDUCTOR:
        if wi[2] <= 0.0:
            return s
        s.wo = reflect_local(wi)
        s.pdf = 1.0
        s.is_delta = 1
        s.lobe = LOBE_DELTA_REFLECTION
        s.weight = wp.cw_mul(fresnel_conductor(wi[2], mat.eta, mat.k), mat.specular_reflectance)
        s.valid = 1
    elif mat.kind == MAT_ROUGHCONDUCTOR:
        if wi[2] <= 0.0:
            return s
        s.wo = reflect_about(wi, microfacet_sample(microfacet_of(mat), wi, u))
        s.lobe = LOBE_GLOSSY_REFLECTION
        evaluate = 1
    elif mat.kind == MAT_DIELECTRIC:
        fr = fresnel_dielectric(wi[2], mat.ior)
        s.is_delta = 1
        s.valid = 1
        if u_lobe <= fr.r:
            s.wo = reflect_local(wi)
            s.pdf = fr.r
            s.weight = mat.specular_reflectance
            s.lobe = LOBE_DELTA_REFLECTION
        else:
            s.wo = wp.vec3(-fr.eta_ti * wi[0], -fr.eta_ti * wi[1], fr.cos_t)
            s.pdf = 1.0 - fr.r
            s.lobe = LOBE_DELTA_TRANSMISSION
            s.eta = fr.eta_it
            s.weight = mat.specular_transmittance * (fr.eta_ti * fr.eta_ti)
    elif mat.kind == MAT_THINDIELECTRIC:
        fr = fresnel_dielectric(wp.abs(wi[2]), mat.ior)
        r = fr.r
        if r < 1.0:
            t = 1.0 - r
            r = r + t * t * r / (1.0 - r * r)  # inter-reflections inside the slab
        s.is_delta = 1
        s.valid = 1
        if u_lobe <= r:
            s.wo = reflect_local(wi)
            s.pdf = r
            s.weight = mat.specular_reflectance
            s.lobe = LOBE_DELTA_REFLECTION
        else:
            s.wo = -wi
            s.pdf = 1.0 - r
            s.lobe = LOBE_DELTA_TRANSMISSION
            s.weight = mat.specular_transmittance
    elif mat.kind == MAT_ROUGHDIELECTRIC:
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
        evaluate = 1
    elif mat.kind == MAT_PLASTIC:
        if wi[2] <= 0.0:
            return s
        f_i = fresnel_dielectric(wi[2], mat.ior).r
        p_spec = plastic_specular_probability(mat, f_i)
        if u_lobe < p_spec:
            s.wo = reflect_local(wi)
            s.pdf = p_spec
            s.is_delta = 1
            s.weight = mat.specular_reflectance * (f_i / p_spec)
            s.valid = 1
            s.lobe = LOBE_DELTA_REFLECTION
        else:
            s.wo = square_to_cosine_hemisphere(u)
            s.lobe = LOBE_DIFFUSE_REFLECTION
            evaluate = 1
    elif mat.kind == MAT_ROUGHPLASTIC:
        if wi[2] <= 0.0:
            return s
        if u_lobe < roughplastic_specular_probability(mat, coat_transmittance(mat, wi[2])):
            s.wo = reflect_about(wi, microfacet_sample(microfacet_of(mat), wi, u))
            s.lobe = LOBE_GLOSSY_REFLECTION
        else:
            s.wo = square_to_cosine_hemisphere(u)
            s.lobe = LOBE_DIFFUSE_REFLECTION
        evaluate = 1
    if evaluate != 0:
        # Directions on the wrong side (or where the lobe is zero) have pdf or eval 0: invalid.
        s.pdf = bsdf_pdf(mat, wi, s.wo)
        if s.pdf > 0.0:
            f = bsdf_eval(mat, wi, s.wo)
            if f[0] > 0.0 or f[1] > 0.0 or f[2] > 0.0:
                s.weight = f / s.pdf
                s.valid = 1
    if s.valid == 0:
        s.lobe = 0
    if flipped:
        s.wo = flip_z(s.wo)
    return s


# ----------------------------------------------------------------------------- lobes
@wp.func
def smooth_lobe(mat: Material, wi: wp.vec3, wo: wp.vec3) -> int:
    """The one non-delta lobe that can scatter wi into wo, for materials with at most one such
    lobe on each side (all but roughplastic); 0 for delta-only materials."""
    if mat.kind == MAT_DIFFUSE or mat.kind == MAT_PLASTIC:
        return LOBE_DIFFUSE_REFLECTION
    if mat.kind == MAT_ROUGHCONDUCTOR:
        return LOBE_GLOSSY_REFLECTION
    if mat.kind == MAT_ROUGHDIELECTRIC:
        return wp.where(wi[2] * wo[2] > 0.0, LOBE_GLOSSY_REFLECTION, LOBE_GLOSSY_TRANSMISSION)
    return 0


@wp.func(inline=False)
def bsdf_eval_lobes(mat: Material, wi_in: wp.vec3, wo_in: wp.vec3, lobes: int) -> wp.vec3:
    """bsdf_eval restricted to the lobes in the mask `lobes` (delta lobes evaluate to 0 anyway)."""
    if mat.kind == MAT_ROUGHPLASTIC:
        return roughplastic_eval_parts(mat, to_front(mat, wi_in, wi_in), to_front(mat, wi_in, wo_in), lobes)
    if smooth_lobe(mat, wi_in, wo_in) & lobes == 0:
        return wp.vec3(0.0)
    return bsdf_eval(mat, wi_in, wo_in)


@wp.func(inline=False)
def bsdf_pdf_lobes(mat: Material, wi_in: wp.vec3, wo_in: wp.vec3, lobes: int) -> float:
    """bsdf_pdf restricted to the lobes in `lobes`: the density of choosing one of them and then
    sampling wo (the single-lobe pdf of ReSTIR PT's lobe-separated path BSDF)."""
    if mat.kind == MAT_ROUGHPLASTIC:
        return roughplastic_pdf_parts(mat, to_front(mat, wi_in, wi_in), to_front(mat, wi_in, wo_in), lobes)
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
    if mat.kind == MAT_DIFFUSE or mat.kind == MAT_PLASTIC or mat.kind == MAT_ROUGHPLASTIC:
        return True
    if mat.kind == MAT_ROUGHCONDUCTOR or mat.kind == MAT_ROUGHDIELECTRIC:
        return linear_roughness(mat) > threshold
    return False
