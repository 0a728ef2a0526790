"""Discrete sampling tables built on the host: Walker alias tables and 2-D piecewise-constant CDFs."""
import numpy as np


def alias_table(weights: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Vose's alias method. Returns (prob, alias, pmf); sampling bin i then coin < prob[i]."""
    w = np.asarray(weights, np.float64)
    if w.size == 0 or w.sum() <= 0:
        raise ValueError("alias table needs positive total weight")
    pmf = w / w.sum()
    n = len(w)
    scaled = pmf * n
    prob = np.ones(n)
    alias = np.arange(n)
    small = [i for i in range(n) if scaled[i] < 1.0]
    large = [i for i in range(n) if scaled[i] >= 1.0]
    while small and large:
        s, l_ = small.pop(), large.pop()
        prob[s] = scaled[s]
        alias[s] = l_
        scaled[l_] = scaled[l_] + scaled[s] - 1.0
        (small if scaled[l_] < 1.0 else large).append(l_)
    for i in small + large:
        prob[i] = 1.0
    return prob.astype(np.float32), alias.astype(np.int32), pmf


def cdf_1d(weights: np.ndarray) -> np.ndarray:
    c = np.concatenate([[0.0], np.cumsum(np.asarray(weights, np.float64))])
    if c[-1] <= 0:
        c = np.linspace(0.0, 1.0, len(c))
    else:
        c /= c[-1]
    c[-1] = 1.0
    return c


def env_tables(lum: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Lat-long map luminance (H, W) -> marginal cdf (H+1), conditional cdfs (H*(W+1))."""
    h, w = lum.shape
    sin_t = np.sin((np.arange(h) + 0.5) / h * np.pi)
    weight = lum * sin_t[:, None]
    cond = np.concatenate([cdf_1d(row) for row in weight])
    marginal = cdf_1d(weight.sum(1))
    return marginal.astype(np.float32), cond.astype(np.float32)
