"""U3 / the CRIS toy (docs/validation.md#level-1-toy-statistical-tests;
docs/guide/suffix_restir.md): a joint integral estimated with a
prefix weight times a conditional suffix weight, W_y x W_{x|y}, the suffix resampled across the
suffix reservoirs of other prefixes, with the production resampling core (ris_stream, ris_merge,
ris_finalize, the generalized balance weight).

I = integral over [0,1]^2 of g(y) h(y, x) dx dy. A "prefix" y is resampled from C uniform
candidates with target g (its W_y). Its suffix x is resampled conditionally on y from: a fresh
canonical candidate, and the suffix reservoirs (x_j, W_j) of K other prefixes y_j (independent
of y; each resampled from uniform candidates with target h(y_j, .)), shifted into y's domain by
T_j(x) = (x + y - y_j) mod 1 (J = 1), with generalized balance MIS over the K + 1 techniques;
its W_{x|y} makes g(y) W_y h(y, x) W_{x|y} an unbiased estimate of I when the suffixes'
randomness is independent of y's given y (conditional independence).

The violating variant selects the prefix by the joint target g(y_k) h(y_k, x_k) of each prefix
candidate and its own suffix candidate, then uses that suffix candidate as the canonical one
while claiming W_y for the marginal target g: x's distribution given y is then not the one
W_{x|y} assumes, and the estimate is biased. z-tests over N = 2^20 independent trials (alpha 1e-4
each); the minimum detectable relative bias is printed.
"""
import numpy as np
import pytest
import warp as wp
from scipy import stats as sps

from restir.device.rng import rng_key, rng_uniform
from restir.resampling.mis import balance_weight, techniques_vec
from restir.resampling.ris import ris_finalize, ris_init, ris_merge, ris_stream

PI = 3.14159265358979


@wp.func
def g(y: float) -> float:
    return 0.3 + y * y


@wp.func
def h(y: float, x: float) -> float:
    c = wp.cos(2.0 * PI * (x - y))
    return (1.0 + 0.8 * c) * (0.5 + x)


@wp.func
def shift(x: float, y_from: float, y_to: float) -> float:
    v = x + y_to - y_from
    return v - wp.floor(v)


@wp.kernel
def cris_kernel(candidates: int, K: int, violate: int, seed: int, out: wp.array(dtype=float)):
    t = wp.tid()
    key = rng_key(wp.uint32(seed), wp.uint32(0), wp.uint32(0), wp.uint32(t))
    dim = int(0)
    # ---- the prefix y: RIS over uniform candidates, target g (or, violating, the joint target)
    s = ris_init()
    y = float(0.0)
    x_joint = float(0.0)
    for c in range(candidates):
        yc = rng_uniform(key, wp.uint32(dim))
        xc = rng_uniform(key, wp.uint32(dim + 1))
        dim += 2
        p = g(yc)
        if violate != 0:
            p = g(yc) * h(yc, xc)
        s = ris_stream(s, p / float(candidates), p, 1.0, c, rng_uniform(key, wp.uint32(dim)))
        dim += 1
        if s.selected == c:
            y = yc
            x_joint = xc
    W_y = s.w_sum / (g(y) * 1.0)  # the W of the marginal target g (M handled as 1/candidates in w)
    # ---- the other prefixes' suffix reservoirs: y_j uniform, x_j resampled with target h(y_j, .)
    ys = techniques_vec()
    xs = techniques_vec()
    Ws = techniques_vec()
    for j in range(K):
        ys[j + 1] = rng_uniform(key, wp.uint32(dim))
        dim += 1
        sj = ris_init()
        for c in range(4):
            xc = rng_uniform(key, wp.uint32(dim))
            p = h(ys[j + 1], xc)
            sj = ris_stream(sj, p / 4.0, p, 1.0, c, rng_uniform(key, wp.uint32(dim + 1)))
            dim += 2
            if sj.selected == c:
                xs[j + 1] = xc
        Ws[j + 1] = ris_finalize(sj, 1.0).W
    # ---- the canonical suffix candidate in y's domain
    xs[0] = rng_uniform(key, wp.uint32(dim))
    dim += 1
    if violate != 0:
        xs[0] = x_joint
    Ws[0] = 1.0
    ys[0] = y
    # ---- conditional resampling of x across the K + 1 techniques (balance MIS, J = 1)
    sx = ris_init()
    x_sel = float(0.0)
    for i in range(K + 1):
        xi = shift(xs[i], ys[i], y)  # technique i's sample in y's domain
        d = techniques_vec()
        for k in range(K + 1):  # each technique's density at xi, in its own domain
            d[k] = h(ys[k], shift(xi, y, ys[k]))
        m = balance_weight(d, K + 1, i)
        sx = ris_merge(sx, m, h(y, xi), 1.0, Ws[i], 1.0, i, rng_uniform(key, wp.uint32(dim)))
        dim += 1
        if sx.selected == i:
            x_sel = xi
    W_x = ris_finalize(sx, 1.0).W
    out[t] = g(y) * W_y * h(y, x_sel) * W_x


def exact() -> float:
    n = 4000
    u = (np.arange(n) + 0.5) / n
    Y, X = np.meshgrid(u, u, indexing="ij")
    return float(np.mean((0.3 + Y ** 2) * (1 + 0.8 * np.cos(2 * np.pi * (X - Y))) * (0.5 + X)))


def run(candidates, K, violate, n=1 << 20, seed=5):
    out = wp.zeros(n, dtype=float, device="cpu")
    wp.launch(cris_kernel, dim=n, inputs=[candidates, K, violate, seed, out], device="cpu")
    v = out.numpy().astype(np.float64)
    I = exact()
    se = v.std(ddof=1) / np.sqrt(n)
    z = (v.mean() - I) / se
    mdb = (sps.norm.isf(0.5e-4) + 0.84) * se / I
    return v.mean(), I, z, mdb


@pytest.mark.parametrize("candidates,K", [(1, 0), (1, 3), (4, 3), (4, 8)])
def test_cris_is_unbiased(candidates, K):
    est, I, z, mdb = run(candidates, K, 0)
    print(f"C={candidates} K={K}: {est:.6f} vs {I:.6f}, z = {z:+.2f}, MDB {100 * mdb:.3f}%")
    assert abs(z) < sps.norm.isf(0.5e-4) and mdb < 0.005


def test_violating_conditional_independence_is_biased():
    est, I, z, mdb = run(4, 3, 1)
    print(f"violating: {est:.6f} vs {I:.6f}, z = {z:+.2f} ({100 * (est / I - 1):+.2f}%)")
    assert abs(z) > 10
