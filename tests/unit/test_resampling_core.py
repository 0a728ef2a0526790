"""Resampling core, Level 0 (D1, D7) and Level 1 (U1) of TESTING.md.

Chi-square and z tests here use alpha = 1e-4 per test (Bonferroni inside a test where noted).
"""
import numpy as np
import pytest
import warp as wp
from scipy import stats as sps

from restir.device.rng import rng_key, rng_uniform
from restir.resampling.mis import (balance_weight, constant_binary_weight, constant_weight_biased,
                                   pairwise_canonical_term, pairwise_neighbor_weight, techniques_vec)
from restir.resampling.ris import cap_confidence, ris_contribution_weight, ris_init, ris_stream
from restir.validation.stats import chi2_test

MIS_PAIRWISE, MIS_BALANCE, MIS_CONSTANT_BINARY, MIS_CONSTANT_BIASED = 0, 1, 2, 3


# ----------------------------------------------------------------------------- D1: MIS weights sum to one
@wp.kernel
def mis_sum_kernel(kind: int, seed: wp.uint32, sums: wp.array(dtype=float), any_nonzero: wp.array(dtype=wp.int32)):
    t = wp.tid()
    key = rng_key(seed, wp.uint32(0), wp.uint32(0), wp.uint32(t))
    k = 1 + int(rng_uniform(key, wp.uint32(0)) * 16.0)           # configured neighbour count
    d = techniques_vec()   # d[j]: density of technique j at y (0 = shift failed or zero target)
    M = techniques_vec()
    valid = techniques_vec()  # neighbours valid by geometry (decided before any sample)
    V = int(0)
    for j in range(k + 1):
        u = rng_uniform(key, wp.uint32(10 + 4 * j))
        M[j] = wp.where(u < 0.1, 0.0, 64.0 * rng_uniform(key, wp.uint32(11 + 4 * j)))
        p_hat = wp.where(rng_uniform(key, wp.uint32(12 + 4 * j)) < 0.2, 0.0, 10.0 * rng_uniform(key, wp.uint32(13 + 4 * j)))
        fail = rng_uniform(key, wp.uint32(200 + j)) < 0.2
        d[j] = wp.where(fail and j > 0, 0.0, p_hat * M[j])
        valid[j] = 1.0
        if j > 0:
            if rng_uniform(key, wp.uint32(300 + j)) < 0.25:
                valid[j] = 0.0
            else:
                V += 1
    total = float(0.0)
    nz = int(0)
    if kind == 0:
        # canonical weight at y, then each valid neighbour's weight at the same y; normalized by V+1
        mc = float(1.0)
        for j in range(1, k + 1):
            if valid[j] > 0.0:
                mc += pairwise_canonical_term(d[0], d[j], k)
        total = mc
        for j in range(1, k + 1):
            if valid[j] > 0.0:
                total += pairwise_neighbor_weight(d[j], d[0], k)
        total = total / float(V + 1)
        nz = 1
    else:
        dv = techniques_vec()
        Mv = techniques_vec()
        n = int(0)
        for j in range(k + 1):
            if valid[j] > 0.0:
                dv[n] = d[j]
                Mv[n] = M[j]
                n += 1
        for i in range(n):
            if dv[i] > 0.0:
                nz = 1
                if kind == 1:
                    total += balance_weight(dv, n, i)
                elif kind == 2:
                    total += constant_binary_weight(dv, Mv, n, i)
                else:
                    total += constant_weight_biased(Mv, n, i)
    sums[t] = total
    any_nonzero[t] = nz


def mis_sums(kind, n=1_000_000):
    sums = wp.zeros(n, dtype=float, device="cpu")
    nz = wp.zeros(n, dtype=wp.int32, device="cpu")
    wp.launch(mis_sum_kernel, dim=n, inputs=[kind, wp.uint32(17), sums, nz], device="cpu")
    return sums.numpy(), nz.numpy() == 1


@pytest.mark.parametrize("kind", [MIS_PAIRWISE, MIS_BALANCE, MIS_CONSTANT_BINARY])
def test_mis_weights_sum_to_one(kind):
    s, nz = mis_sums(kind)
    assert nz.sum() > 900_000
    np.testing.assert_allclose(s[nz], 1.0, atol=1e-5)


def test_constant_1_over_M_is_not_a_partition_of_unity():
    """Negative control: ignoring which techniques can produce y breaks (iii) (TESTING.md 5.0)."""
    s, nz = mis_sums(MIS_CONSTANT_BIASED)
    assert np.mean(np.abs(s[nz] - 1) > 1e-3) > 0.3


def test_pairwise_canonical_term_pairs_with_neighbor_weight():
    # For the same y: the canonical's share for neighbour i plus neighbour i's weight is 1.
    @wp.kernel
    def k_(out: wp.array(dtype=float)):
        i = wp.tid()
        key = rng_key(wp.uint32(5), wp.uint32(0), wp.uint32(0), wp.uint32(i))
        d_c = rng_uniform(key, wp.uint32(0)) * 5.0
        d_i = wp.where(rng_uniform(key, wp.uint32(1)) < 0.3, 0.0, rng_uniform(key, wp.uint32(2)) * 5.0)
        k = 1 + int(rng_uniform(key, wp.uint32(3)) * 8.0)
        out[i] = pairwise_canonical_term(d_c, d_i, k) + pairwise_neighbor_weight(d_i, d_c, k)

    out = wp.zeros(100_000, dtype=float, device="cpu")
    wp.launch(k_, dim=100_000, inputs=[out], device="cpu")
    np.testing.assert_allclose(out.numpy(), 1.0, atol=1e-6)


# ----------------------------------------------------------------------------- D7: reservoir algebra
@wp.kernel
def stream_kernel(weights: wp.array(dtype=float), seed: wp.uint32, sel: wp.array(dtype=wp.int32), W: wp.array(dtype=float),
                  wsum: wp.array(dtype=float), M: wp.array(dtype=float)):
    t = wp.tid()
    key = rng_key(seed, wp.uint32(0), wp.uint32(0), wp.uint32(t))
    s = ris_init()
    for i in range(weights.shape[0]):
        s = ris_stream(s, weights[i], 2.0 * float(i + 1), 1.0, i, rng_uniform(key, wp.uint32(i)))
    sel[t] = s.selected
    W[t] = ris_contribution_weight(s, 1.0)
    wsum[t] = s.w_sum
    M[t] = s.M


def run_stream(w, n):
    outs = [wp.zeros(n, dtype=ty, device="cpu") for ty in (wp.int32, float, float, float)]
    wp.launch(stream_kernel, dim=n, inputs=[wp.array(np.asarray(w, np.float32), device="cpu"), wp.uint32(9), *outs], device="cpu")
    return [o.numpy() for o in outs]


def test_selection_frequencies_and_W():
    w = np.array([0.0, 1.0, 3.0, 0.0, 0.5, 1e4, 2.0, 0.0, 7.0])
    sel, W, wsum, M = run_stream(w, 1_000_000)
    counts = np.bincount(sel, minlength=len(w))
    assert counts[w == 0].sum() == 0, "a zero-weight candidate was selected"
    keep = w > 0
    p, stat, dof = chi2_test(counts[keep], w[keep] / w.sum() * len(sel), min_expected=0)
    assert p > 1e-4, (stat, dof)
    np.testing.assert_allclose(wsum, w.sum(), rtol=1e-6)
    np.testing.assert_allclose(W, w.sum() / (2.0 * (sel + 1)), rtol=1e-6)  # W = w_sum / p_hat(y)
    assert np.all(M == len(w))  # zero-weight inputs still add their confidence


def test_all_zero_and_nonfinite_inputs():
    sel, W, _, M = run_stream([0.0, 0.0, 0.0], 100)
    assert np.all(sel == -1) and np.all(W == 0) and np.all(M == 3)
    sel, W, wsum, _ = run_stream([1.0, np.nan, np.inf, 1.0], 10000)
    assert set(np.unique(sel)) == {0, 3} and np.allclose(wsum, 2.0)


def test_confidence_cap():
    @wp.kernel
    def k_(x: wp.array(dtype=float), cap: float, out: wp.array(dtype=float)):
        i = wp.tid()
        out[i] = cap_confidence(x[i], cap)

    x = np.array([0.0, 1.0, 5.0, 20.0, 100.0], np.float32)
    out = wp.zeros(5, dtype=float, device="cpu")
    wp.launch(k_, dim=5, inputs=[wp.array(x, device="cpu"), 20.0, out], device="cpu")
    np.testing.assert_array_equal(out.numpy(), [0, 1, 5, 20, 20])
    wp.launch(k_, dim=5, inputs=[wp.array(x, device="cpu"), 0.0, out], device="cpu")
    np.testing.assert_array_equal(out.numpy(), x)


# ----------------------------------------------------------------------------- U1: E[W | Y] = 1 / p_Y(Y)
@wp.func
def toy_target(x: float, hole: int) -> float:
    if hole != 0 and x >= 0.4 and x < 0.5:
        return 0.0
    s = wp.sin(3.0 * 3.14159265358979 * x)
    return 0.05 + s * s


@wp.kernel
def ucw_kernel(M: int, hole: int, seed: wp.uint32, Y: wp.array(dtype=float), W: wp.array(dtype=float)):
    t = wp.tid()
    key = rng_key(seed, wp.uint32(0), wp.uint32(0), wp.uint32(t))
    s = ris_init()
    y = float(0.0)
    for i in range(M):
        x = -1.0 + wp.sqrt(1.0 + 3.0 * rng_uniform(key, wp.uint32(2 * i)))   # x ~ p(x) = 2/3 (1 + x)
        p = (2.0 / 3.0) * (1.0 + x)
        p_hat = toy_target(x, hole)
        s = ris_stream(s, p_hat / p / float(M), p_hat, 1.0, i, rng_uniform(key, wp.uint32(2 * i + 1)))
        if s.selected == i:
            y = x
    Y[t] = y
    W[t] = ris_contribution_weight(s, 1.0)


@pytest.mark.parametrize("M", [1, 4, 32])
@pytest.mark.parametrize("hole", [0, 1])
def test_unbiased_contribution_weight(M, hole):
    n, B = 4_000_000, 50
    Y = wp.zeros(n, dtype=float, device="cpu")
    W = wp.zeros(n, dtype=float, device="cpu")
    wp.launch(ucw_kernel, dim=n, inputs=[M, hole, wp.uint32(M + 10 * hole), Y, W], device="cpu")
    y, w = Y.numpy().astype(np.float64), W.numpy().astype(np.float64)
    b = np.minimum((y * B).astype(int), B - 1)
    A = np.bincount(b, weights=w, minlength=B) / n                 # mean of W 1{Y in bin}
    A2 = np.bincount(b, weights=w * w, minlength=B) / n
    se = np.sqrt(np.maximum(A2 - A * A, 1e-30) / n)
    expected = np.full(B, 1.0 / B)
    if hole:  # no coverage where p_hat = 0: those bins are empty, the others unaffected
        empty = (np.arange(B) >= 20) & (np.arange(B) < 25)
        assert np.all(A[empty] == 0)
        expected[empty] = 0.0
    z = np.where(expected > 0, (A - expected) / se, 0.0)
    crit = sps.norm.isf(1e-4 / (2 * B))
    assert np.all(np.abs(z) < crit), (np.abs(z).max(), crit)
    assert np.sum(z * z) < sps.chi2.isf(1e-4, B)
    # and F = f(Y) W estimates the integral of f over the covered domain
    for f, exact in ((lambda x: x * x, 1 / 3), (lambda x: (x > 0.7).astype(float), 0.3)):
        vals = f(y) * w
        covered_exact = exact
        if hole:  # the integral over [0.4, 0.5), which no sample can reach, is missing
            covered_exact = exact - f(np.linspace(0.4, 0.5, 100001)).mean() * 0.1
        assert abs(vals.mean() - covered_exact) < 5 * vals.std() / np.sqrt(n)
