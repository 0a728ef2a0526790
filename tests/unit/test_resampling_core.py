"""Resampling core: D1, D7 (docs/validation.md#level-0-deterministic-property-tests) and U1
(docs/validation.md#level-1-toy-statistical-tests).

Chi-square and z tests here use alpha = 1e-4 per test (Bonferroni inside a test where noted).
"""
import numpy as np
import pytest
import warp as wp
from scipy import stats as sps

from restir.device.rng import rng_key, rng_uniform
from restir.resampling.mis import (balance_weight, constant_binary_weight, constant_weight_biased,
                                   pairwise_add_neighbor, pairwise_init, pairwise_normalization, talbot_weight2,
                                   techniques_vec)
from restir.resampling.ris import (NO_CAP_RATIO, cap_history, ris_contribution_weight, ris_finalize, ris_init,
                                   ris_merge, ris_stream)
from restir.validation.stats import chi2_test

MIS_PAIRWISE, MIS_BALANCE, MIS_CONSTANT_BINARY, MIS_CONSTANT_BIASED = 0, 1, 2, 3


# ----------------------------------------------------------------------------- D1: MIS weights sum to one
MAX_K = 16


@wp.kernel
def pairwise_stage_kernel(k: wp.array(dtype=wp.int32), valid: wp.array2d(dtype=wp.int32), d: wp.array2d(dtype=float),
                          m_c: wp.array(dtype=float), m_i: wp.array2d(dtype=float), norm: wp.array(dtype=float)):
    """The accumulator driven as the spatial stages drive it, for one sample y seen by every
    technique: d[t, 0] = p_hat_c(y) M_c, d[t, j] = technique j's density at y (0: failed shift or
    zero target or zero confidence); neighbours invalid by geometry are skipped before any sample."""
    t = wp.tid()
    acc = pairwise_init(k[t])
    for j in range(k[t]):
        if valid[t, j] == 0:
            continue
        acc = pairwise_add_neighbor(acc, d[t, j + 1], d[t, 0], d[t, 0], d[t, j + 1])
        m_i[t, j] = acc.m_i
    m_c[t] = acc.m_c
    norm[t] = pairwise_normalization(acc)


def random_technique_sets(n, seed=17):
    """Random technique sets with the cases that break naive weights: neighbours invalid by
    geometry, zero confidences, failed shifts and zero targets (each on a known fraction)."""
    rng = np.random.default_rng(seed)
    k = rng.integers(1, MAX_K + 1, n).astype(np.int32)
    valid = (rng.random((n, MAX_K)) >= 0.25).astype(np.int32)
    M = np.where(rng.random((n, MAX_K + 1)) < 0.1, 0.0, 64 * rng.random((n, MAX_K + 1)))
    p_hat = np.where(rng.random((n, MAX_K + 1)) < 0.2, 0.0, 10 * rng.random((n, MAX_K + 1)))
    failed = rng.random((n, MAX_K + 1)) < 0.2
    failed[:, 0] = False  # the canonical technique has no shift
    d = np.where(failed, 0.0, p_hat * M).astype(np.float32)
    return k, valid, d


def test_pairwise_weights_of_the_stage_accumulator(device):
    """D1 for pairwise MIS as the stages compute it (resampling/mis.py's accumulator), against
    the weights written out from their definition (docs/theory/mis.md#pairwise-mis) in float64 here: the
    neighbour weight d_i / (d_i + d_c / k), the canonical weight 1 + sum of (d_c / k) / (d_i + d_c / k)
    (a full 1 where d_i = 0), the normalisation V + 1 with V the neighbours valid by geometry, and
    for every y that some technique can produce, weights / (V + 1) summing to 1."""
    n = 200_000
    k, valid, d = random_technique_sets(n)
    in_k = np.arange(MAX_K)[None, :] < k[:, None]
    use = (valid == 1) & in_k
    # the generator must produce every hard case, in quantity (these can fail if it regresses)
    assert np.mean(use & (d[:, 1:] == 0)) > 0.1 and np.mean(d[:, 0] == 0) > 0.2 and np.mean(in_k & (valid == 0)) > 0.1
    out = [wp.zeros(n, dtype=float, device=device), wp.zeros((n, MAX_K), dtype=float, device=device),
           wp.zeros(n, dtype=float, device=device)]
    wp.launch(pairwise_stage_kernel, dim=n, inputs=[wp.array(k, device=device), wp.array(valid, device=device),
                                                    wp.array(d, device=device), *out], device=device)
    m_c, m_i, norm = (o.numpy().astype(np.float64) for o in out)
    d64 = d.astype(np.float64)
    a = d64[:, :1] / k[:, None]                               # d_c / k
    dn = d64[:, 1:]
    with np.errstate(divide="ignore", invalid="ignore"):
        share = np.where(dn > 0, a / (dn + a), 1.0)
        w_n = np.where(dn > 0, dn / (dn + a), 0.0)
    expect_m_c = 1.0 + np.where(use, share, 0.0).sum(1)
    V = use.sum(1)
    np.testing.assert_allclose(norm, V + 1)
    np.testing.assert_allclose(m_c, expect_m_c, rtol=1e-5)
    np.testing.assert_allclose(np.where(use, m_i, 0.0), np.where(use, w_n, 0.0), rtol=1e-5, atol=1e-7)
    covered = (d64[:, 0] > 0) | np.any(use & (dn > 0), axis=1)
    total = (m_c + np.where(use, m_i, 0.0).sum(1)) / norm
    assert covered.mean() > 0.5
    np.testing.assert_allclose(total[covered], 1.0, atol=1e-5)


@wp.kernel
def mis_sum_kernel(kind: int, seed: wp.uint32, sums: wp.array(dtype=float), any_nonzero: wp.array(dtype=wp.int32)):
    t = wp.tid()
    key = rng_key(seed, wp.uint32(0), wp.uint32(0), wp.uint32(t))
    n = 1 + int(rng_uniform(key, wp.uint32(0)) * 16.0)           # techniques valid by geometry
    d = techniques_vec()   # d[j]: density of technique j at y (0 = shift failed or zero target)
    M = techniques_vec()
    for j in range(n):
        u = rng_uniform(key, wp.uint32(10 + 4 * j))
        M[j] = wp.where(u < 0.1, 0.0, 64.0 * rng_uniform(key, wp.uint32(11 + 4 * j)))
        p_hat = wp.where(rng_uniform(key, wp.uint32(12 + 4 * j)) < 0.2, 0.0, 10.0 * rng_uniform(key, wp.uint32(13 + 4 * j)))
        fail = rng_uniform(key, wp.uint32(200 + j)) < 0.2
        d[j] = wp.where(fail and j > 0, 0.0, p_hat * M[j])
    total = float(0.0)
    nz = int(0)
    for i in range(n):
        if d[i] > 0.0:  # the techniques that can produce y: their weights at y must sum to 1
            nz = 1
            if kind == 1:
                total += balance_weight(d, n, i)
            elif kind == 2:
                total += constant_binary_weight(d, M, n, i)
            else:
                total += constant_weight_biased(M, n, i)
    if kind == 1 and n >= 2:  # the two-technique form the temporal stages use agrees with it
        if wp.abs(talbot_weight2(d[0], d[1], 0) + talbot_weight2(d[0], d[1], 1) - (balance_weight(d, 2, 0) + balance_weight(d, 2, 1))) > 1.0e-6:
            total = -1.0
    sums[t] = total
    any_nonzero[t] = nz


def mis_sums(kind, device, n=1_000_000):
    sums = wp.zeros(n, dtype=float, device=device)
    nz = wp.zeros(n, dtype=wp.int32, device=device)
    wp.launch(mis_sum_kernel, dim=n, inputs=[kind, wp.uint32(17), sums, nz], device=device)
    return sums.numpy(), nz.numpy() == 1


@pytest.mark.parametrize("kind", [MIS_BALANCE, MIS_CONSTANT_BINARY])
def test_mis_weights_sum_to_one(kind, device):
    s, nz = mis_sums(kind, device)
    # about 1 set in 9 has no technique that can produce y (all densities 0): those carry no weight
    assert 0.02 < 1 - nz.mean() < 0.3
    np.testing.assert_allclose(s[nz], 1.0, atol=1e-5)


def test_constant_1_over_M_is_not_a_partition_of_unity(device):
    """Negative control: ignoring which techniques can produce y breaks condition 3
    (docs/validation.md#what-has-to-hold)."""
    s, nz = mis_sums(MIS_CONSTANT_BIASED, device)
    assert np.mean(np.abs(s[nz] - 1) > 1e-3) > 0.3


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


def run_stream(w, n, device):
    outs = [wp.zeros(n, dtype=ty, device=device) for ty in (wp.int32, float, float, float)]
    wp.launch(stream_kernel, dim=n, inputs=[wp.array(np.asarray(w, np.float32), device=device), wp.uint32(9), *outs],
              device=device)
    return [o.numpy() for o in outs]


def test_selection_frequencies_and_W(device):
    w = np.array([0.0, 1.0, 3.0, 0.0, 0.5, 1e4, 2.0, 0.0, 7.0])
    sel, W, wsum, M = run_stream(w, 1_000_000, device)
    counts = np.bincount(sel, minlength=len(w))
    assert counts[w == 0].sum() == 0, "a zero-weight candidate was selected"
    keep = w > 0
    p, stat, dof = chi2_test(counts[keep], w[keep] / w.sum() * len(sel), min_expected=0)
    assert p > 1e-4, (stat, dof)
    np.testing.assert_allclose(wsum, w.sum(), rtol=1e-6)
    np.testing.assert_allclose(W, w.sum() / (2.0 * (sel + 1)), rtol=1e-6)  # W = w_sum / p_hat(y)
    assert np.all(M == len(w))  # zero-weight inputs still add their confidence


def test_all_zero_and_nonfinite_inputs(device):
    sel, W, _, M = run_stream([0.0, 0.0, 0.0], 100, device)
    assert np.all(sel == -1) and np.all(W == 0) and np.all(M == 3)
    sel, W, wsum, _ = run_stream([1.0, np.nan, np.inf, 1.0], 10000, device)
    assert set(np.unique(sel)) == {0, 3} and np.allclose(wsum, 2.0)


@wp.kernel
def merge_kernel(inputs: wp.array2d(dtype=float), norm: float, seed: wp.uint32, sel: wp.array(dtype=wp.int32),
                 W: wp.array(dtype=float), M: wp.array(dtype=float), has: wp.array(dtype=wp.int32)):
    t = wp.tid()
    key = rng_key(seed, wp.uint32(1), wp.uint32(0), wp.uint32(t))
    s = ris_init()
    for i in range(inputs.shape[0]):  # rows: m, p_hat, J, W, M
        s = ris_merge(s, inputs[i, 0], inputs[i, 1], inputs[i, 2], inputs[i, 3], inputs[i, 4], i,
                      rng_uniform(key, wp.uint32(i)))
    f = ris_finalize(s, norm)
    sel[t] = s.selected
    W[t] = f.W
    M[t] = f.M
    has[t] = f.selected


def test_merge_weights_and_finalisation(device):
    """ris_merge selects input i with probability m p_hat J W / w_sum (a failed shift, J = 0, keeps
    its confidence and is never selected); ris_finalize gives W = w_sum / (p_hat(y) norm), M = sum M."""
    rows = np.array([[0.5, 2.0, 1.0, 3.0, 1.0],     # w = 3
                     [0.25, 4.0, 0.0, 9.0, 20.0],   # failed shift: w = 0
                     [1.0, 1.5, 2.0, 1.0, 5.0],     # w = 3
                     [0.1, 3.0, 0.5, 8.0, 0.0],     # w = 1.2, zero confidence
                     [0.0, 7.0, 1.0, 1.0, 2.0]],    # m = 0
                    np.float32)
    w = rows[:, 0].astype(np.float64) * rows[:, 1] * rows[:, 2] * rows[:, 3]
    n = 400_000
    out = [wp.zeros(n, dtype=ty, device=device) for ty in (wp.int32, float, float, wp.int32)]
    wp.launch(merge_kernel, dim=n, inputs=[wp.array(rows, device=device), 3.0, wp.uint32(4), *out], device=device)
    sel, W, M, has = (o.numpy() for o in out)
    counts = np.bincount(sel, minlength=len(rows))
    assert counts[w == 0].sum() == 0
    p, stat, dof = chi2_test(counts[w > 0], w[w > 0] / w.sum() * n, min_expected=0)
    assert p > 1e-4, (stat, dof)
    np.testing.assert_allclose(W, w.sum() / (rows[sel, 1] * 3.0), rtol=1e-6)
    assert np.all(M == rows[:, 4].sum()) and np.all(has == 1)
    out = [wp.zeros(4, dtype=ty, device=device) for ty in (wp.int32, float, float, wp.int32)]
    wp.launch(merge_kernel, dim=4, inputs=[wp.array(rows[[1, 4]], device=device), 1.0, wp.uint32(5), *out], device=device)
    sel, W, M, has = (o.numpy() for o in out)
    assert np.all(sel == -1) and np.all(W == 0) and np.all(M == 22) and np.all(has == 0)


def test_confidence_cap(device):
    """cap_history, the one cap of a history's confidence: cap_ratio x the current confidence,
    "no cap" (ratio <= 0) a cap at NO_CAP_RATIO x, and a current confidence of 0 caps at 0 (it
    once read as "no cap" and let M grow without bound on pixels with no smooth lobe)."""
    @wp.kernel
    def k_(x: wp.array(dtype=float), ratio: float, current: float, out: wp.array(dtype=float)):
        i = wp.tid()
        out[i] = cap_history(x[i], ratio, current)

    def cap(x, ratio, current):
        out = wp.zeros(len(x), dtype=float, device=device)
        wp.launch(k_, dim=len(x), inputs=[wp.array(np.asarray(x, np.float32), device=device), ratio, current, out],
                  device=device)
        return out.numpy()

    x = np.array([0.0, 1.0, 5.0, 20.0, 100.0], np.float32)
    np.testing.assert_array_equal(cap(x, 20.0, 1.0), [0, 1, 5, 20, 20])
    np.testing.assert_array_equal(cap(x, 0.0, 1.0), x)
    np.testing.assert_array_equal(cap(x, 5.0, 2.0), [0, 1, 5, 10, 10])
    np.testing.assert_array_equal(cap(x, 5.0, 0.0), 0.0)
    np.testing.assert_array_equal(cap([1e30], 0.0, 3.0), [NO_CAP_RATIO * 3.0])


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
def test_unbiased_contribution_weight(M, hole, device):
    n, B = 4_000_000, 50
    Y = wp.zeros(n, dtype=float, device=device)
    W = wp.zeros(n, dtype=float, device=device)
    wp.launch(ucw_kernel, dim=n, inputs=[M, hole, wp.uint32(M + 10 * hole), Y, W], device=device)
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
