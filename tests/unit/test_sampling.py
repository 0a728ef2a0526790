"""Level 0/1: sampling warps (round trips, normalization, chi-square), RNG, alias tables, microfacets.

Chi-square tests use alpha = 1e-3 each (a false failure in about one run in a thousand per test).
"""
import numpy as np
import pytest
import warp as wp
from scipy import stats as sps

from restir.device import microfacet as mf
from restir.device import sampling as sp
from restir.device.rng import rng_key, rng_uniform
from restir.scene.light_tables import alias_table
from restir.validation.stats import chi2_test

ALPHA = 1e-3


@wp.kernel
def warps_kernel(u: wp.array(dtype=wp.vec2), out: wp.array2d(dtype=float)):
    i = wp.tid()
    c = sp.square_to_cosine_hemisphere(u[i])
    cu = sp.cosine_hemisphere_to_square(c)
    s = sp.square_to_uniform_sphere(u[i])
    su = sp.uniform_sphere_to_square(s)
    b = sp.square_to_uniform_triangle(u[i])
    bu = sp.uniform_triangle_to_square(b)
    d = sp.square_to_uniform_disk_concentric(u[i])
    du = sp.uniform_disk_concentric_to_square(d)
    t = sp.sample_tent(u[i][0])
    tu = sp.invert_tent(t)
    vals = wp.vector(c[0], c[1], c[2], cu[0], cu[1], s[0], s[1], s[2], su[0], su[1],
                     b[0], b[1], bu[0], bu[1], du[0], du[1], t, tu, sp.cosine_hemisphere_pdf(c), length=19, dtype=float)
    for k in range(19):
        out[i, k] = vals[k]


@pytest.fixture(scope="module")
def warped(device):
    rng = np.random.default_rng(1)
    u = rng.random((200_000, 2)).astype(np.float32)
    u = np.clip(u, 1e-4, 1 - 1e-4)  # round trips are ill-conditioned at the square's edges
    out = wp.zeros((len(u), 19), dtype=float, device=device)
    wp.launch(warps_kernel, dim=len(u), inputs=[wp.array(u, dtype=wp.vec2, device=device), out], device=device)
    return u, out.numpy()


def test_round_trips(warped):
    u, o = warped
    np.testing.assert_allclose(o[:, 3:5], u, atol=2e-3)    # cosine hemisphere
    np.testing.assert_allclose(o[:, 8:10], u, atol=2e-3)   # uniform sphere
    np.testing.assert_allclose(o[:, 12:14], u, atol=2e-3)  # triangle
    np.testing.assert_allclose(o[:, 14:16], u, atol=2e-3)  # concentric disk
    np.testing.assert_allclose(o[:, 17], u[:, 0], atol=2e-4)  # tent


def test_cosine_hemisphere_matches_its_pdf(warped):
    _, o = warped
    c = o[:, 0:3]
    np.testing.assert_allclose(np.linalg.norm(c, axis=1), 1, atol=1e-5)
    np.testing.assert_allclose(o[:, 18], c[:, 2] / np.pi, rtol=1e-5)
    # cos theta of a cosine-distributed direction: P(cos < x) = x^2
    p = sps.kstest(c[:, 2] ** 2, "uniform").pvalue
    assert p > ALPHA


def test_triangle_is_uniform(warped):
    _, o = warped
    b1, b2 = o[:, 10], o[:, 11]
    assert (b1 >= 0).all() and (b2 >= 0).all() and (b1 + b2 <= 1 + 1e-6).all()
    # 10x10 grid on the unit square: cells cut by the diagonal get expected area by exact geometry
    h, _, _ = np.histogram2d(b1, b2, bins=10, range=[[0, 1], [0, 1]])
    g = np.arange(11) / 10
    exp = np.zeros((10, 10))
    for i in range(10):
        for j in range(10):
            xs = np.linspace(g[i], g[i + 1], 201)
            ys = np.clip(1 - xs - g[j], 0, 0.1)
            exp[i, j] = np.trapezoid(ys, xs) * 2 * len(b1)
    p, _, _ = chi2_test(h, exp)
    assert p > ALPHA


def test_tent_matches_its_pdf(warped):
    _, o = warped
    t = o[:, 16]
    edges = np.linspace(-1, 1, 41)
    h, _ = np.histogram(t, edges)
    cdf = lambda x: np.where(x < 0, 0.5 * (x + 1) ** 2, 1 - 0.5 * (1 - x) ** 2)  # noqa: E731
    p, _, _ = chi2_test(h, np.diff(cdf(edges)) * len(t))
    assert p > ALPHA


@wp.kernel
def rng_kernel(seed: wp.uint32, out: wp.array2d(dtype=float)):
    i = wp.tid()
    key = rng_key(seed, wp.uint32(3), wp.uint32(7), wp.uint32(i))
    for d in range(4):
        out[i, d] = rng_uniform(key, wp.uint32(d))


def test_rng_uniform_and_decorrelated(device):
    out = wp.zeros((500_000, 4), dtype=float, device=device)
    wp.launch(rng_kernel, dim=500_000, inputs=[wp.uint32(42), out], device=device)
    x = out.numpy()
    assert (x >= 0).all() and (x < 1).all()
    for d in range(4):
        h, _ = np.histogram(x[:, d], 100, (0, 1))
        assert chi2_test(h, np.full(100, len(x) / 100))[0] > ALPHA / 4
    c = np.corrcoef(x.T)
    assert np.abs(c - np.eye(4)).max() < 5 * 4 / np.sqrt(len(x))  # |r| under ~5 sigma
    # pairs of consecutive dimensions fill the square uniformly
    h, _, _ = np.histogram2d(x[:, 0], x[:, 1], bins=20, range=[[0, 1], [0, 1]])
    assert chi2_test(h, np.full((20, 20), len(x) / 400))[0] > ALPHA


@wp.kernel
def alias_kernel(prob: wp.array(dtype=float), alias: wp.array(dtype=wp.int32), seed: wp.uint32, out: wp.array(dtype=wp.int32)):
    i = wp.tid()
    out[i] = sp.sample_alias(prob, alias, rng_uniform(rng_key(seed, wp.uint32(0), wp.uint32(0), wp.uint32(i)), wp.uint32(0)))


def test_alias_table_frequencies(device):
    w = np.array([0.0, 1.0, 5.0, 0.0, 0.2, 100.0, 3.0, 0.0])
    prob, alias, pmf = alias_table(w)
    n = 1_000_000
    out = wp.zeros(n, dtype=wp.int32, device=device)
    wp.launch(alias_kernel, dim=n, inputs=[wp.array(prob, device=device), wp.array(alias, device=device), wp.uint32(5), out],
              device=device)
    counts = np.bincount(out.numpy(), minlength=len(w))
    assert counts[w == 0].sum() == 0, "a zero-weight entry was selected"
    keep = w > 0
    p, _, _ = chi2_test(counts[keep], pmf[keep] * n, min_expected=0)
    assert p > ALPHA


@wp.kernel
def ndf_kernel(kind: int, au: float, av: float, dirs: wp.array(dtype=wp.vec3), out: wp.array(dtype=float)):
    i = wp.tid()
    d = mf.Microfacet()
    d.kind = kind
    d.alpha_u = au
    d.alpha_v = av
    m = dirs[i]
    out[i] = mf.microfacet_D(d, m) * wp.max(m[2], 0.0)


@pytest.mark.parametrize("kind,au,av", [(0, 0.1, 0.1), (0, 0.5, 0.5), (0, 0.2, 0.05), (1, 0.1, 0.1), (1, 0.6, 0.6), (1, 0.3, 0.08)])
def test_microfacet_D_projected_area_is_one(kind, au, av, device):
    # integral of D(m) cos(theta_m) over the hemisphere = 1, on a fine (theta, phi) grid
    nt, npp = 4000, 256
    t = (np.arange(nt) + 0.5) / nt * (np.pi / 2)
    p = (np.arange(npp) + 0.5) / npp * 2 * np.pi
    T, P = np.meshgrid(t, p, indexing="ij")
    dirs = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], -1).reshape(-1, 3).astype(np.float32)
    out = wp.zeros(len(dirs), dtype=float, device=device)
    wp.launch(ndf_kernel, dim=len(dirs), inputs=[kind, au, av, wp.array(dirs, dtype=wp.vec3, device=device), out], device=device)
    integral = (out.numpy().reshape(nt, npp) * np.sin(T)).sum() * (np.pi / 2 / nt) * (2 * np.pi / npp)
    assert abs(integral - 1) < 2e-3


@wp.kernel
def vndf_kernel(kind: int, au: float, av: float, wi: wp.vec3, dirs: wp.array(dtype=wp.vec3), out: wp.array(dtype=float)):
    i = wp.tid()
    d = mf.Microfacet()
    d.kind = kind
    d.alpha_u = au
    d.alpha_v = av
    out[i] = mf.microfacet_pdf(d, wi, dirs[i])


@pytest.mark.parametrize("kind,au,av,theta", [(0, 0.1, 0.1, 30), (0, 0.5, 0.5, 75), (0, 0.3, 0.1, 60),
                                              (1, 0.2, 0.2, 45), (1, 0.6, 0.3, 80)])
def test_visible_normal_density_integrates_to_one(kind, au, av, theta, device):
    """D_wi(m) = G1(wi, m) <wi, m> D(m) / cos(theta_i) is a density over m only with the exact
    Smith G1 (for Beckmann: the erf form, not the rational fit used in shading)."""
    nt, npp = 3000, 256
    t = (np.arange(nt) + 0.5) / nt * (np.pi / 2)
    p = (np.arange(npp) + 0.5) / npp * 2 * np.pi
    T, P = np.meshgrid(t, p, indexing="ij")
    dirs = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], -1).reshape(-1, 3).astype(np.float32)
    wi = wp.vec3(np.sin(np.radians(theta)) * 0.6, np.sin(np.radians(theta)) * 0.8, np.cos(np.radians(theta)))
    out = wp.zeros(len(dirs), dtype=float, device=device)
    wp.launch(vndf_kernel, dim=len(dirs), inputs=[kind, au, av, wi, wp.array(dirs, dtype=wp.vec3, device=device), out],
              device=device)
    integral = (out.numpy().reshape(nt, npp) * np.sin(T)).sum() * (np.pi / 2 / nt) * (2 * np.pi / npp)
    assert abs(integral - 1) < 3e-3
