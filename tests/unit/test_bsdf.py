"""BSDF sampling against its pdf (chi-square), consistency of sample/pdf/eval, Fresnel, delta lobes.

Each chi-square test has alpha = 1e-3. The pdf is integrated per bin by a midpoint rule on an
8x8 sub-grid; lobes are kept wide enough (alpha >= 0.1) for that to be accurate.
"""
import numpy as np
import pytest
import warp as wp

from restir.device.bsdf import Material, bsdf_eval, bsdf_pdf, bsdf_sample
from restir.device.fresnel import fresnel_conductor, fresnel_dielectric
from restir.device.rng import rng_key, rng_uniform, rng_uniform2
from restir.device.types import (MAT_CONDUCTOR, MAT_DIELECTRIC, MAT_DIFFUSE, MAT_DIFFUSE_TRANSMISSION, MAT_METALLIC_ROUGHNESS,
                                 MAT_ROUGHCONDUCTOR,
                                 MAT_PLASTIC, MAT_ROUGHDIELECTRIC, MAT_ROUGHPLASTIC, MAT_THINDIELECTRIC, MICROFACET_BECKMANN,
                                 MICROFACET_GGX)
from restir.validation.stats import chi2_test, expected_counts, histogram_directions, integration_points

ALPHA = 1e-3
N = 1_000_000
NT, NP, SUB = 40, 80, 8


_ONES = wp.array(np.ones(2, np.float32), dtype=float, device="cpu")
_KEEP = []


def material(kind, alpha=(0.1, 0.1), dist=MICROFACET_GGX, ior=1.5, twosided=0, metallic=0.0):
    m = Material()
    m.kind = int(kind)
    m.twosided = twosided
    m.reflectance = wp.vec3(0.8, 0.5, 0.2)
    m.specular_reflectance = wp.vec3(1.0, 0.9, 0.8)
    m.specular_transmittance = wp.vec3(1.0, 1.0, 1.0)
    m.eta = wp.vec3(0.2, 0.92, 1.1)
    m.k = wp.vec3(3.9, 2.45, 2.14)
    m.ior = ior
    m.distribution = int(dist)
    m.alpha_u, m.alpha_v = alpha
    m.specular_sampling_weight = 1.0 / (1.0 + 0.5)
    m.fdr_int = 0.6
    m.nonlinear = 0
    m.opacity = 1.0  # unmasked (upload.material_struct's default)
    m.metallic = metallic
    if kind == MAT_ROUGHPLASTIC:
        from restir.scene.coat_tables import roughplastic_tables

        table, m.fdr_int = roughplastic_tables("ggx" if dist == MICROFACET_GGX else "beckmann", alpha[0], ior)
        m.coat_transmittance = wp.array(table.astype(np.float32), dtype=float, device="cpu")
        _KEEP.append(m.coat_transmittance)
    else:
        m.coat_transmittance = _ONES
    return m


@wp.kernel
def sample_kernel(mat: Material, wi: wp.vec3, seed: wp.uint32, wo: wp.array(dtype=wp.vec3),
                  weight: wp.array(dtype=wp.vec3), pdf: wp.array(dtype=float), valid: wp.array(dtype=wp.int32),
                  pdf_check: wp.array(dtype=float), eval_check: wp.array(dtype=wp.vec3), delta: wp.array(dtype=wp.int32)):
    i = wp.tid()
    key = rng_key(seed, wp.uint32(0), wp.uint32(0), wp.uint32(i))
    s = bsdf_sample(mat, wi, rng_uniform(key, wp.uint32(0)), rng_uniform2(key, wp.uint32(1)))
    wo[i] = s.wo
    weight[i] = s.weight
    pdf[i] = s.pdf
    valid[i] = s.valid
    pdf_check[i] = bsdf_pdf(mat, wi, s.wo)
    eval_check[i] = bsdf_eval(mat, wi, s.wo)
    delta[i] = s.is_delta


@wp.kernel
def pdf_kernel(mat: Material, wi: wp.vec3, dirs: wp.array(dtype=wp.vec3), out: wp.array(dtype=float)):
    i = wp.tid()
    out[i] = bsdf_pdf(mat, wi, dirs[i])


def run_sampler(mat, wi, n=N, seed=1, with_delta=False):
    arrs = [wp.zeros(n, dtype=t, device="cpu") for t in (wp.vec3, wp.vec3, float, wp.int32, float, wp.vec3, wp.int32)]
    wp.launch(sample_kernel, dim=n, inputs=[mat, wp.vec3(*wi), wp.uint32(seed), *arrs], device="cpu")
    out = [a.numpy() for a in arrs]
    return out if with_delta else out[:6]


def direction(theta_deg, phi_deg=30.0, below=False):
    t, p = np.radians(theta_deg), np.radians(phi_deg)
    v = np.array([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)])
    if below:
        v[2] = -v[2]
    return v.astype(np.float32)


def bumped(m, tilt_deg, shadowing=True):
    """m under a bump map whose normal is tilted by tilt_deg from ns (bump_n0: ns in the tilted
    frame), as bounce.material_at sets it; the BSDF then carries bump.bump_factor."""
    t = np.radians(tilt_deg)
    m.bumped = 1
    m.bump_n0 = wp.vec3(float(np.sin(t)), 0.0, float(np.cos(t)))
    m.bump_alpha2 = float(min(0.125 * np.tan(t) ** 2, 1.0)) if shadowing else 0.0
    return m


def masked(m, opacity):
    """m inside a mask of the given opacity (the null lobe with probability 1 - opacity)."""
    m.masked = 1
    m.opacity = float(opacity)
    return m


SMOOTH_CASES = [
    ("diffuse", material(MAT_DIFFUSE), direction(40)),
    ("diffuse-twosided-back", material(MAT_DIFFUSE, twosided=1), direction(40, below=True)),
    ("beckmann-0.1", material(MAT_ROUGHCONDUCTOR, (0.1, 0.1), MICROFACET_BECKMANN), direction(30)),
    ("beckmann-0.4-grazing", material(MAT_ROUGHCONDUCTOR, (0.4, 0.4), MICROFACET_BECKMANN), direction(80)),
    ("beckmann-aniso", material(MAT_ROUGHCONDUCTOR, (0.3, 0.1), MICROFACET_BECKMANN), direction(45)),
    ("ggx-0.1", material(MAT_ROUGHCONDUCTOR, (0.1, 0.1)), direction(30)),
    ("ggx-0.5-grazing", material(MAT_ROUGHCONDUCTOR, (0.5, 0.5)), direction(85)),
    ("ggx-aniso", material(MAT_ROUGHCONDUCTOR, (0.1, 0.35)), direction(50)),
    ("roughdielectric-ggx-outside", material(MAT_ROUGHDIELECTRIC, (0.3, 0.3)), direction(35)),
    ("roughdielectric-ggx-inside", material(MAT_ROUGHDIELECTRIC, (0.3, 0.3)), direction(25, below=True)),
    ("roughdielectric-ggx-inside-tir", material(MAT_ROUGHDIELECTRIC, (0.2, 0.2)), direction(60, below=True)),
    ("roughdielectric-beckmann", material(MAT_ROUGHDIELECTRIC, (0.25, 0.25), MICROFACET_BECKMANN, ior=1.33), direction(55)),
    ("plastic-diffuse-lobe", material(MAT_PLASTIC, ior=1.49), direction(50)),
    ("plastic-grazing", material(MAT_PLASTIC, ior=1.49), direction(85)),
    ("roughplastic-ggx", material(MAT_ROUGHPLASTIC, (0.2, 0.2), ior=1.49), direction(40)),
    ("roughplastic-beckmann-grazing", material(MAT_ROUGHPLASTIC, (0.3, 0.3), MICROFACET_BECKMANN, ior=1.49), direction(80)),
    ("diffuse-transmission", material(MAT_DIFFUSE_TRANSMISSION, twosided=1), direction(40)),
    ("diffuse-transmission-back", material(MAT_DIFFUSE_TRANSMISSION, twosided=1), direction(70, below=True)),
    ("metallic-roughness-dielectric", material(MAT_METALLIC_ROUGHNESS, (0.2, 0.2)), direction(40)),
    ("metallic-roughness-half", material(MAT_METALLIC_ROUGHNESS, (0.35, 0.35), metallic=0.5), direction(70)),
    ("metallic-roughness-metal", material(MAT_METALLIC_ROUGHNESS, (0.15, 0.15), metallic=1.0), direction(20)),
    ("metallic-roughness-twosided-back", material(MAT_METALLIC_ROUGHNESS, (0.3, 0.3), twosided=1, metallic=0.3),
     direction(50, below=True)),
    # bump-mapped (the tilted frame's zero region and the shadowing term; wo with phi = 180 deg
    # from the tilt falls between the two surfaces first)
    ("bumped-diffuse", bumped(material(MAT_DIFFUSE), 35), direction(40)),
    ("bumped-diffuse-twosided-back", bumped(material(MAT_DIFFUSE, twosided=1), 30), direction(40, below=True)),
    ("bumped-roughplastic", bumped(material(MAT_ROUGHPLASTIC, (0.2, 0.2), ior=1.49), 25), direction(60, 200)),
    ("bumped-roughdielectric-inside", bumped(material(MAT_ROUGHDIELECTRIC, (0.3, 0.3)), 20, False),
     direction(25, below=True)),
    # masked: non-delta samples carry pdf * opacity, the rest pass through (test_mask_null_lobe)
    ("masked-diffuse", masked(material(MAT_DIFFUSE), 0.6), direction(40)),
    ("masked-roughplastic-twosided-back", masked(material(MAT_ROUGHPLASTIC, (0.2, 0.2), ior=1.49, twosided=1), 0.35),
     direction(50, below=True)),
    ("masked-bumped-diffuse", masked(bumped(material(MAT_DIFFUSE), 30), 0.8), direction(40)),
]


@pytest.mark.parametrize("name,mat,wi", SMOOTH_CASES, ids=[c[0] for c in SMOOTH_CASES])
def test_sampling_matches_pdf(name, mat, wi):
    wo, weight, pdf, valid, pdf_check, eval_check, delta = run_sampler(mat, wi, with_delta=True)
    # Delta lobes (plastic's coat) are checked separately; the pdf function covers the rest.
    ok = (valid == 1) & (delta == 0)
    # the pdf a sample reports is the pdf function's value, and weight = eval / pdf
    np.testing.assert_allclose(pdf[ok], pdf_check[ok], rtol=2e-3, atol=1e-6)
    np.testing.assert_allclose(weight[ok] * pdf[ok, None], eval_check[ok], rtol=2e-3, atol=1e-5)
    # histogram of sampled directions against the pdf integrated over each bin
    pts = integration_points(NT, NP, SUB).reshape(-1, 3).astype(np.float32)
    out = wp.zeros(len(pts), dtype=float, device="cpu")
    wp.launch(pdf_kernel, dim=len(pts), inputs=[mat, wp.vec3(*wi), wp.array(pts, dtype=wp.vec3, device="cpu"), out], device="cpu")
    expected = expected_counts(out.numpy(), NT, NP, SUB, N)
    observed = histogram_directions(wo[ok], NT, NP)
    p, stat, dof = chi2_test(observed, expected)
    assert p > ALPHA, f"{name}: chi2={stat:.1f} dof={dof} p={p:.2e}"
    # the pdf integrates to the probability that sampling succeeds
    frac = ok.mean()
    assert abs(expected.sum() / N - frac) < 0.01 + 5 * np.sqrt(frac * (1 - frac) / N), (expected.sum() / N, frac)


def fresnel_reference(cos_i, n_complex):
    """Unpolarized Fresnel reflectance of a (possibly absorbing) interface, from complex amplitudes."""
    sin2 = 1 - cos_i ** 2
    cos_t = np.sqrt(1 - sin2 / n_complex ** 2 + 0j)
    rs = (cos_i - n_complex * cos_t) / (cos_i + n_complex * cos_t)
    rp = (n_complex * cos_i - cos_t) / (n_complex * cos_i + cos_t)
    return 0.5 * (abs(rs) ** 2 + abs(rp) ** 2)


@wp.kernel
def fresnel_kernel(cos_i: wp.array(dtype=float), eta: float, eta_c: wp.vec3, k_c: wp.vec3,
                   r_diel: wp.array(dtype=float), r_cond: wp.array(dtype=wp.vec3)):
    i = wp.tid()
    r_diel[i] = fresnel_dielectric(cos_i[i], eta).r
    r_cond[i] = fresnel_conductor(cos_i[i], eta_c, k_c)


def test_fresnel_against_complex_reference():
    c = np.linspace(-1, 1, 2001).astype(np.float32)
    c = c[c != 0]
    rd = wp.zeros(len(c), dtype=float, device="cpu")
    rc = wp.zeros(len(c), dtype=wp.vec3, device="cpu")
    eta_c, k_c = (0.2, 0.92, 1.1), (3.9, 2.45, 2.14)
    wp.launch(fresnel_kernel, dim=len(c), inputs=[wp.array(c, device="cpu"), 1.5, wp.vec3(*eta_c), wp.vec3(*k_c), rd, rc], device="cpu")
    ref_d = np.where(c > 0, fresnel_reference(np.abs(c), 1.5), fresnel_reference(np.abs(c), 1 / 1.5))
    np.testing.assert_allclose(rd.numpy(), ref_d, atol=2e-5)
    for ch in range(3):
        ref_c = fresnel_reference(np.abs(c), eta_c[ch] + 1j * k_c[ch])
        np.testing.assert_allclose(rc.numpy()[:, ch], ref_c, atol=2e-5)


@pytest.mark.parametrize("below", [False, True])
def test_smooth_dielectric_lobes(below):
    wi = direction(30 if below else 50, below=below)  # inside: below the 41.8 deg critical angle
    wo, weight, pdf, valid, _, _ = run_sampler(material(MAT_DIELECTRIC), wi, n=200_000)
    assert valid.all()
    refl = np.sign(wo[:, 2]) == np.sign(wi[2])
    eta = 1.5 if not below else 1 / 1.5
    F = fresnel_reference(abs(wi[2]), eta)
    se = np.sqrt(F * (1 - F) / len(wo))
    assert abs(refl.mean() - F) < 4.5 * se
    # reflection mirrors wi; refraction obeys Snell's law with radiance scaled by 1/eta^2
    np.testing.assert_allclose(wo[refl], np.tile([-wi[0], -wi[1], wi[2]], (refl.sum(), 1)), atol=1e-6)
    sin_t = np.linalg.norm(wo[~refl, :2], axis=1)
    np.testing.assert_allclose(sin_t, np.linalg.norm(wi[:2]) / eta, rtol=1e-4)
    np.testing.assert_allclose(weight[~refl, 0], 1 / eta ** 2, rtol=1e-5)
    np.testing.assert_allclose(pdf[refl], F, rtol=1e-4)


def test_thin_dielectric_and_conductor():
    wi = direction(60)
    wo, weight, pdf, valid, _, _ = run_sampler(material(MAT_THINDIELECTRIC), wi, n=200_000)
    R = fresnel_reference(wi[2], 1.5)
    R2 = R + (1 - R) ** 2 * R / (1 - R * R)
    refl = wo[:, 2] > 0
    assert abs(refl.mean() - R2) < 4.5 * np.sqrt(R2 * (1 - R2) / len(wo))
    np.testing.assert_allclose(wo[~refl], -np.tile(wi, ((~refl).sum(), 1)), atol=1e-6)
    wo, weight, pdf, valid, _, _ = run_sampler(material(MAT_CONDUCTOR), wi, n=1000)
    ref = [fresnel_reference(wi[2], e + 1j * k) * s for e, k, s in zip((0.2, 0.92, 1.1), (3.9, 2.45, 2.14), (1.0, 0.9, 0.8))]
    np.testing.assert_allclose(weight[0], ref, rtol=1e-4)


def test_one_sided_is_black_from_behind():
    wi = direction(40, below=True)
    for kind in (MAT_DIFFUSE, MAT_ROUGHCONDUCTOR):
        _, weight, _, valid, _, _ = run_sampler(material(kind), wi, n=1000)
        assert not valid.any() and not weight.any()


def test_plastic_specular_lobe():
    """Coat reflection: chosen with the documented probability and weighted F_i / p."""
    wi = direction(60)
    wo, weight, pdf, valid, _, _, delta = run_sampler(material(MAT_PLASTIC, ior=1.49), wi, n=200_000, with_delta=True)
    F = fresnel_reference(wi[2], 1.49)
    w = 1.0 / 1.5
    p_spec = F * w / (F * w + (1 - F) * (1 - w))
    d = delta == 1
    assert abs(d.mean() - p_spec) < 4.5 * np.sqrt(p_spec * (1 - p_spec) / len(d))
    np.testing.assert_allclose(wo[d], np.tile([-wi[0], -wi[1], wi[2]], (d.sum(), 1)), atol=1e-6)
    np.testing.assert_allclose(weight[d], np.tile(np.array([1.0, 0.9, 0.8]) * F / p_spec, (d.sum(), 1)), rtol=1e-4)


@pytest.mark.parametrize("kind,opacity", [(MAT_DIFFUSE, 0.6), (MAT_CONDUCTOR, 0.7), (MAT_ROUGHCONDUCTOR, 0.0),
                                          (MAT_DIELECTRIC, 1.0)])
def test_mask_null_lobe(kind, opacity):
    """A mask passes straight through (wo = -wi, weight 1, pdf 1 - opacity, delta, eta 1) with
    probability 1 - opacity; otherwise the nested sample, its weight unchanged and a delta lobe's
    pdf scaled by the opacity (Mitsuba 3's mask.cpp); eval and pdf are the kind's times opacity."""
    wi = direction(50)
    n = 200_000
    base = material(kind)
    m = masked(material(kind), opacity)
    wo, weight, pdf, valid, pdf_check, eval_check, delta = run_sampler(m, wi, n=n, with_delta=True)
    wo0, weight0, pdf0, valid0, pdf_check0, eval_check0, delta0 = run_sampler(base, wi, n=n, with_delta=True)
    null = (delta == 1) & np.all(np.abs(wo + wi) < 1e-6, axis=1)
    if kind == MAT_DIELECTRIC:  # a smooth dielectric's own refraction at 50 deg is not straight through
        assert not null.any()
    se = np.sqrt(opacity * (1 - opacity) / n) + 1e-9
    assert abs(null.mean() - (1 - opacity)) < 4.5 * se
    if null.any():
        np.testing.assert_allclose(weight[null], 1.0)
        np.testing.assert_allclose(pdf[null], 1 - opacity, rtol=1e-6)
    # same numbers: the nested part sees u_lobe / opacity, so its samples are the unmasked ones of
    # those numbers; checked through the statistics of the scattering samples
    sc = valid.astype(bool) & ~null
    if opacity > 0:
        ok0 = valid0.astype(bool)
        for a, b in ((weight[sc], weight0[ok0]), (wo[sc, 2:], wo0[ok0, 2:])):
            np.testing.assert_allclose(a.mean(0), b.mean(0), rtol=2e-3, atol=6 * (a.std(0).max() + 1e-6) / np.sqrt(sc.sum()))
        d = delta[sc] == 1
        if d.any():
            # each delta sample's pdf is opacity times one of the unmasked delta lobes' pdfs
            lobes = np.unique(np.round(pdf0[ok0][delta0[ok0] == 1], 5))
            ratio = pdf[sc][d][:, None] / opacity
            assert np.all(np.min(np.abs(ratio - lobes[None, :]), axis=1) < 1e-4), lobes
    # eval and pdf at the unmasked material's sampled directions: the factor opacity exactly
    ok0 = (valid0 == 1) & (delta0 == 0)
    if ok0.any():
        m_eval = run_eval(m, wi, wo0[ok0])
        np.testing.assert_allclose(m_eval[0], opacity * eval_check0[ok0], rtol=1e-6, atol=1e-12)
        np.testing.assert_allclose(m_eval[1], opacity * pdf_check0[ok0], rtol=1e-6, atol=1e-12)


@wp.kernel
def eval_pdf_kernel(mat: Material, wi: wp.vec3, dirs: wp.array(dtype=wp.vec3), f: wp.array(dtype=wp.vec3),
                    pdf: wp.array(dtype=float)):
    i = wp.tid()
    f[i] = bsdf_eval(mat, wi, dirs[i])
    pdf[i] = bsdf_pdf(mat, wi, dirs[i])


def run_eval(mat, wi, dirs):
    f = wp.zeros(len(dirs), dtype=wp.vec3, device="cpu")
    p = wp.zeros(len(dirs), dtype=float, device="cpu")
    wp.launch(eval_pdf_kernel, dim=len(dirs), inputs=[mat, wp.vec3(*wi), wp.array(dirs.astype(np.float32), dtype=wp.vec3,
                                                                                  device="cpu"), f, p], device="cpu")
    return f.numpy(), p.numpy()
