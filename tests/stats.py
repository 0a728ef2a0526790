"""Statistical test machinery: chi-square goodness of fit on the sphere, z-tests, MDB.

False-failure rates: every test states its alpha. Chi-square tests use alpha = 1e-3 per test;
z-tests split alpha = 1e-3 per configuration between image, tile and pixel levels (Bonferroni),
as TESTING.md section 5.2 describes.
"""
import numpy as np
from scipy import stats as sps

Z_POWER = 0.8416  # one-sided normal quantile for 80% power


def sphere_bins(n_theta: int, n_phi: int):
    """Bins uniform in (cos theta, phi): equal solid angle each."""
    return np.linspace(-1, 1, n_theta + 1), np.linspace(0, 2 * np.pi, n_phi + 1)


def histogram_directions(dirs: np.ndarray, n_theta: int, n_phi: int) -> np.ndarray:
    z = np.clip(dirs[:, 2], -1, 1)
    phi = np.mod(np.arctan2(dirs[:, 1], dirs[:, 0]), 2 * np.pi)
    zb, pb = sphere_bins(n_theta, n_phi)
    h, _, _ = np.histogram2d(z, phi, bins=[zb, pb])
    return h


def integration_points(n_theta: int, n_phi: int, sub: int) -> np.ndarray:
    """Midpoints of a sub x sub grid in every bin, as unit vectors; shape (n_theta*sub, n_phi*sub, 3)."""
    z = np.linspace(-1, 1, n_theta * sub + 1)
    z = 0.5 * (z[1:] + z[:-1])
    p = np.linspace(0, 2 * np.pi, n_phi * sub + 1)
    p = 0.5 * (p[1:] + p[:-1])
    Z, P = np.meshgrid(z, p, indexing="ij")
    r = np.sqrt(np.maximum(0, 1 - Z * Z))
    return np.stack([r * np.cos(P), r * np.sin(P), Z], -1)


def expected_counts(pdf_values: np.ndarray, n_theta: int, n_phi: int, sub: int, n: int) -> np.ndarray:
    """pdf (solid angle) on `integration_points` -> expected counts per bin (midpoint rule)."""
    cell = (2.0 / (n_theta * sub)) * (2 * np.pi / (n_phi * sub))
    pv = pdf_values.reshape(n_theta, sub, n_phi, sub)
    return pv.sum(axis=(1, 3)) * cell * n


def chi2_test(observed: np.ndarray, expected: np.ndarray, min_expected: float = 5.0):
    """Pearson chi-square with low-expectation bins pooled (as pbrt and Mitsuba do).

    Returns (p_value, statistic, dof). The pooled bin also holds samples in bins with zero pdf,
    so a sampler that lands where its pdf is 0 fails.
    """
    o = observed.ravel().astype(np.float64)
    e = expected.ravel().astype(np.float64)
    keep = e >= min_expected
    obs = list(o[keep])
    exp = list(e[keep])
    pooled_o, pooled_e = o[~keep].sum(), e[~keep].sum()
    if pooled_e > 0 or pooled_o > 0:
        obs.append(pooled_o)
        exp.append(max(pooled_e, 1e-12))
    obs, exp = np.array(obs), np.array(exp)
    # Totals may differ (samples outside the tabulated domain, pdf integration error):
    # compare shapes, and test the total separately in the caller.
    exp *= obs.sum() / exp.sum()
    stat = float(((obs - exp) ** 2 / exp).sum())
    dof = len(obs) - 1
    return float(sps.chi2.sf(stat, dof)), stat, dof


def z_threshold(alpha: float, tests: int = 1) -> float:
    """Two-sided normal threshold with a Bonferroni split over `tests`."""
    return float(sps.norm.isf(alpha / (2 * tests)))


def mdb(z_crit: float, std_err: float, mean: float) -> float:
    """Minimum detectable relative bias at 80% power (TESTING.md 5.2)."""
    return (z_crit + Z_POWER) * std_err / max(abs(mean), 1e-30)


def skewness(x: np.ndarray) -> float:
    return float(sps.skew(np.asarray(x).ravel()))


def tile_means(img: np.ndarray, var: np.ndarray, tile: int):
    """Means and variances-of-mean over tile x tile blocks of independent pixels."""
    h, w = img.shape[:2]
    h2, w2 = h - h % tile, w - w % tile
    m = img[:h2, :w2].reshape(h2 // tile, tile, w2 // tile, tile, -1).mean(axis=(1, 3))
    v = var[:h2, :w2].reshape(h2 // tile, tile, w2 // tile, tile, -1).sum(axis=(1, 3)) / tile ** 4
    return m, v
