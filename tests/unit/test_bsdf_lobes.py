"""Lobes of the BSDFs: restricted eval/pdf partition the full ones, sampled lobes are chosen with
the probabilities the restricted pdfs integrate to, and the roughness classification that picks
reconnection vertices (docs/theory/restir_pt.md#the-lobe-separated-path-bsdf and #the-reconnection-vertex).

The frequency test is a z-test per (material, lobe) at alpha = 1e-3 (Bonferroni over the cells):
each lobe's sampling frequency against the integral of its restricted pdf over the sphere,
estimated independently of the sampler by uniform directions. With 400k samples and 400k
directions the smallest detectable difference is about 0.5 percentage points.
"""
import numpy as np
import pytest
import warp as wp
from scipy import stats as sps

from restir.device.bsdf import (Material, bsdf_eval, bsdf_eval_lobes, bsdf_has_rough_component, bsdf_pdf,
                                bsdf_pdf_lobes, bsdf_sample, lobe_is_rough)
from restir.device.rng import rng_key, rng_uniform, rng_uniform2
from restir.device.sampling import square_to_uniform_sphere
from restir.device.types import (LOBE_DELTA_REFLECTION, LOBE_DELTA_TRANSMISSION, LOBE_DIFFUSE_REFLECTION,
                                 LOBE_DIFFUSE_TRANSMISSION, LOBE_GLOSSY_REFLECTION, LOBE_GLOSSY_TRANSMISSION,
                                 LOBES_ALL, MAT_CONDUCTOR, MAT_DIELECTRIC, MAT_DIFFUSE, MAT_DIFFUSE_TRANSMISSION,
                                 MAT_METALLIC_ROUGHNESS, MAT_PLASTIC,
                                 MAT_ROUGHCONDUCTOR, MAT_ROUGHDIELECTRIC, MAT_ROUGHPLASTIC, MAT_THINDIELECTRIC)

from .test_bsdf import material

LOBES = [LOBE_DIFFUSE_REFLECTION, LOBE_DIFFUSE_TRANSMISSION, LOBE_GLOSSY_REFLECTION, LOBE_GLOSSY_TRANSMISSION,
         LOBE_DELTA_REFLECTION, LOBE_DELTA_TRANSMISSION]
MATERIALS = {
    "diffuse": lambda: material(MAT_DIFFUSE),
    "conductor": lambda: material(MAT_CONDUCTOR),
    "roughconductor": lambda: material(MAT_ROUGHCONDUCTOR, alpha=(0.3, 0.15)),
    "dielectric": lambda: material(MAT_DIELECTRIC),
    "thindielectric": lambda: material(MAT_THINDIELECTRIC),
    "roughdielectric": lambda: material(MAT_ROUGHDIELECTRIC, alpha=(0.3, 0.3)),
    "plastic": lambda: material(MAT_PLASTIC),
    "roughplastic": lambda: material(MAT_ROUGHPLASTIC, alpha=(0.2, 0.2)),
    "roughplastic-twosided": lambda: material(MAT_ROUGHPLASTIC, alpha=(0.2, 0.2), twosided=1),
    "metallic-roughness": lambda: material(MAT_METALLIC_ROUGHNESS, alpha=(0.25, 0.25), metallic=0.4),
    "diffuse-transmission": lambda: material(MAT_DIFFUSE_TRANSMISSION, twosided=1),
}


@wp.kernel
def partition_kernel(mat: Material, wi: wp.array(dtype=wp.vec3), wo: wp.array(dtype=wp.vec3),
                     lobe_eval: wp.array2d(dtype=wp.vec3), lobe_pdf: wp.array2d(dtype=float),
                     full_eval: wp.array(dtype=wp.vec3), full_pdf: wp.array(dtype=float)):
    i = wp.tid()
    for b in range(6):
        lobe_eval[i, b] = bsdf_eval_lobes(mat, wi[i], wo[i], 1 << b)
        lobe_pdf[i, b] = bsdf_pdf_lobes(mat, wi[i], wo[i], 1 << b)
    lobe_eval[i, 6] = bsdf_eval_lobes(mat, wi[i], wo[i], LOBES_ALL)
    lobe_pdf[i, 6] = bsdf_pdf_lobes(mat, wi[i], wo[i], LOBES_ALL)
    full_eval[i] = bsdf_eval(mat, wi[i], wo[i])
    full_pdf[i] = bsdf_pdf(mat, wi[i], wo[i])


def random_dirs(rng, n):
    v = rng.normal(size=(n, 3))
    return (v / np.linalg.norm(v, axis=1, keepdims=True)).astype(np.float32)


@pytest.mark.parametrize("name", list(MATERIALS))
def test_restricted_eval_and_pdf_partition_the_full_ones(name, device):
    mat = MATERIALS[name]()
    rng = np.random.default_rng(3)
    n = 20_000
    wi, wo = random_dirs(rng, n), random_dirs(rng, n)
    wi[: n // 2, 2] = np.abs(wi[: n // 2, 2])  # half from the front side, where every lobe is non-zero
    wi[n // 2:, 2] = np.where(rng.random(n - n // 2) < 0.5, 1, -1) * np.abs(wi[n // 2:, 2])
    outs = [wp.zeros((n, 7), dtype=wp.vec3, device=device), wp.zeros((n, 7), dtype=float, device=device),
            wp.zeros(n, dtype=wp.vec3, device=device), wp.zeros(n, dtype=float, device=device)]
    wp.launch(partition_kernel, dim=n, inputs=[mat, wp.array(wi, dtype=wp.vec3, device=device),
                                               wp.array(wo, dtype=wp.vec3, device=device), *outs], device=device)
    le, lp, fe, fp = (o.numpy().astype(np.float64) for o in outs)
    np.testing.assert_allclose(le[:, :6].sum(1), fe, rtol=1e-5, atol=1e-7)
    np.testing.assert_allclose(lp[:, :6].sum(1), fp, rtol=1e-5, atol=1e-7)
    np.testing.assert_allclose(le[:, 6], fe, rtol=1e-6, atol=0)
    np.testing.assert_allclose(lp[:, 6], fp, rtol=1e-6, atol=0)
    if name in ("roughplastic", "roughplastic-twosided"):  # both lobes are really there, and separate
        front = (wi[:, 2] > 0.2) & (wo[:, 2] > 0.2)
        assert np.all(lp[front, 0] > 0) and np.mean(lp[front, 2] > 0) > 0.5


@wp.kernel
def lobe_sample_kernel(mat: Material, wi: wp.vec3, seed: wp.uint32, lobe: wp.array(dtype=wp.int32),
                       own_pdf: wp.array(dtype=float), uniform_pdf: wp.array2d(dtype=float)):
    i = wp.tid()
    key = rng_key(seed, wp.uint32(0), wp.uint32(0), wp.uint32(i))
    s = bsdf_sample(mat, wi, rng_uniform(key, wp.uint32(0)), rng_uniform2(key, wp.uint32(1)))
    lobe[i] = s.lobe
    own_pdf[i] = 0.0
    if s.valid != 0 and s.is_delta == 0:
        own_pdf[i] = bsdf_pdf_lobes(mat, wi, s.wo, s.lobe)
    # independent of the sampler: restricted pdfs at a uniform direction, for their integrals
    d = square_to_uniform_sphere(rng_uniform2(key, wp.uint32(7)))
    for b in range(4):
        uniform_pdf[i, b] = bsdf_pdf_lobes(mat, wi, d, 1 << b) * 4.0 * 3.14159265358979
    uniform_pdf[i, 4] = bsdf_pdf(mat, wi, d) * 4.0 * 3.14159265358979


@pytest.mark.parametrize("name", list(MATERIALS))
def test_sampled_lobe_frequencies(name, device):
    mat = MATERIALS[name]()
    wi = np.array([0.45, -0.2, 0.87], np.float32)
    wi /= np.linalg.norm(wi)
    n = 400_000
    outs = [wp.zeros(n, dtype=wp.int32, device=device), wp.zeros(n, dtype=float, device=device),
            wp.zeros((n, 5), dtype=float, device=device)]
    wp.launch(lobe_sample_kernel, dim=n, inputs=[mat, wp.vec3(*wi), wp.uint32(11), *outs], device=device)
    lobe, own_pdf, up = (o.numpy() for o in outs)
    up = up.astype(np.float64)
    valid = lobe != 0
    smooth = np.isin(lobe, LOBES[:4])
    assert np.all(np.isin(lobe[valid], LOBES))
    assert np.all(own_pdf[smooth] > 0), "a sample's own lobe must be able to produce it"
    crit = sps.norm.isf(1e-3 / (2 * 5 * len(MATERIALS)))
    # smooth lobes: frequency = integral of the restricted pdf
    for b in range(4):
        freq = np.mean(lobe == LOBES[b])
        integral, se_i = up[:, b].mean(), up[:, b].std() / np.sqrt(n)
        se = np.hypot(np.sqrt(max(freq * (1 - freq), 1e-12) / n), se_i)
        assert abs(freq - integral) < crit * se + 1e-12, (name, LOBES[b], freq, integral)
    # delta lobes together: 1 - integral of the smooth pdf, less what invalid samples lose
    delta = np.isin(lobe, LOBES[4:]).mean()
    if name in ("conductor", "dielectric", "thindielectric"):
        assert delta == 1.0
    elif name == "plastic":
        integral, se_i = up[:, 4].mean(), up[:, 4].std() / np.sqrt(n)
        se = np.hypot(np.sqrt(delta * (1 - delta) / n), se_i)
        assert abs(delta - (1 - integral)) < crit * se, (delta, 1 - integral)
    else:
        assert delta == 0.0


@wp.kernel
def rough_kernel(mat: Material, threshold: float, out: wp.array(dtype=wp.int32)):
    for b in range(6):
        out[b] = wp.where(lobe_is_rough(mat, 1 << b, threshold), 1, 0)
    out[6] = wp.where(bsdf_has_rough_component(mat, threshold), 1, 0)


@pytest.mark.parametrize("name,alpha,expect_glossy_rough,expect_component", [
    ("diffuse", None, None, True),                  # None: the material has no glossy lobe to classify
    ("conductor", None, None, False),
    ("dielectric", None, None, False),
    ("roughconductor", (0.09, 0.2), True, True),    # linear roughness sqrt(0.09) = 0.3 > 0.2
    ("roughconductor", (0.01, 0.3), False, False),  # smoother direction: sqrt(0.01) = 0.1
    ("roughdielectric", (0.0225, 0.0225), False, False),  # 0.15
    ("plastic", None, None, True),                  # delta coat, diffuse base
    ("roughplastic", (0.01, 0.01), False, True),    # smooth coat, diffuse base
])
def test_roughness_classification(name, alpha, expect_glossy_rough, expect_component, device):
    kinds = {"diffuse": MAT_DIFFUSE, "conductor": MAT_CONDUCTOR, "dielectric": MAT_DIELECTRIC,
             "roughconductor": MAT_ROUGHCONDUCTOR, "roughdielectric": MAT_ROUGHDIELECTRIC, "plastic": MAT_PLASTIC,
             "roughplastic": MAT_ROUGHPLASTIC}
    mat = material(kinds[name], alpha=alpha or (0.1, 0.1))
    out = wp.zeros(7, dtype=wp.int32, device=device)
    wp.launch(rough_kernel, dim=1, inputs=[mat, 0.2, out], device=device)
    o = out.numpy()
    assert o[0] == 1 and o[1] == 1          # diffuse lobes are always rough
    assert o[4] == 0 and o[5] == 0          # delta lobes never
    if expect_glossy_rough is not None:
        assert o[2] == o[3] == int(expect_glossy_rough)
    assert o[6] == int(expect_component)
