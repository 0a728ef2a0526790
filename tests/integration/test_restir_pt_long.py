"""ReSTIR PT over frames and parameters (TESTING.md 5.7, 5.8), on the emissive-cap sphere (every
non-emitting pixel has the same analytic value; exact reference).

- I1-I3 (I2, I3 in the slow tier): image means over independent runs for neighbour counts k, temporal caps and spatial
  rounds; a weighted regression of the mean on the parameter must have |slope / SE| < 3.5 (the
  seed report's "more neighbours, brighter" shows as a slope), and every configuration passes
  the z-test against the exact value.
- L1: frame t alone (not an average) is unbiased for t in {0, 1, 2, 4, 8, 15}: independent runs,
  Bonferroni over the frames (alpha 1e-3 in all).
- L2: the long run with temporal + spatial reuse, k = 8, cap 20 (the settings with which the
  seed report's implementation grew bright spots): no trend in the batch means, no growing
  maxima, nothing non-finite. Fast: 8 seeds x 600 frames; slow: 16 seeds x 5000 frames.
"""
import numpy as np
import pytest

import restir
from restir.scene.builtin import sphere_cap_radiance
from restir.validation import IndependentRuns
from tests.integration.test_path_tracer import ANALYTIC_REL_TOL, check
from tests.integration.test_restir_di import check_no_trend, long_run_trend

CAP = dict(albedo=0.5, radiance=1.0, phi=0.05)
DEPTH = 4
EXACT = sphere_cap_radiance(CAP["albedo"], CAP["radiance"], CAP["phi"], DEPTH)


def sphere(size=16):
    return restir.load_scene("builtin:sphere-cap", width=size, height=size, **CAP)


def run_means(settings, runs=32, frames=8, method="restir-pt"):
    """Per-run image means (non-emitting pixels only: the cap is seen in a few) and the z-test."""
    cfg = restir.RenderConfig(method=method, spp=1, frames=frames, max_depth=DEPTH, settings=settings)
    r = IndependentRuns(sphere(), cfg, runs, 300)
    rep = check(r, EXACT, rel_tol=ANALYTIC_REL_TOL)
    inside = np.abs(r.image.mean(-1) - EXACT) < 0.5 * EXACT
    return r.batches[:, inside].astype(np.float64).mean(axis=(1, 2)), rep.mdb


def check_flat(values, settings_of, method="restir-pt"):
    means, ses = [], []
    for v in values:
        m, mdb = run_means(settings_of(v), method=method)
        means.append(m.mean())
        ses.append(m.std(ddof=1) / np.sqrt(len(m)))
        print(v, f"mean {means[-1]:.6f} +- {ses[-1]:.6f} (exact {EXACT:.6f}), MDB {mdb:.4f}")
    x = np.log(np.asarray(values, float))
    w = 1 / np.asarray(ses) ** 2
    xm = np.sum(w * x) / w.sum()
    slope = np.sum(w * (x - xm) * np.asarray(means)) / np.sum(w * (x - xm) ** 2)
    t = slope * np.sqrt(np.sum(w * (x - xm) ** 2))
    print(f"slope/SE {t:.2f}")
    assert abs(t) < 3.5


def test_invariance_in_k():
    """I1 over k in {1, 2, 4, 8} (one spatial round, no temporal reuse)."""
    check_flat([1, 2, 4, 8], lambda k: {"temporal": False, "spatial.neighbors": k})


@pytest.mark.slow
def test_invariance_in_cap():
    """I2 over temporal.cap in {1, 2, 5, 20, 100} (temporal reuse only)."""
    check_flat([1, 2, 5, 20, 100], lambda c: {"spatial.rounds": 0, "temporal.cap": float(c)})


@pytest.mark.slow
def test_invariance_in_rounds():
    """I3 over spatial.rounds in {1, 2, 3} (no temporal reuse)."""
    check_flat([1, 2, 3], lambda n: {"temporal": False, "spatial.rounds": n})


def test_every_frame_is_unbiased():
    """L1: frames 0, 1, 2, 4, 8, 15 each unbiased over 48 independent runs (defaults)."""
    check_every_frame("restir-pt")


def check_every_frame(method, runs=48, frames_t=(0, 1, 2, 4, 8, 15)):
    from restir.validation.stats import RGBZTest

    imgs = []
    for k in range(runs):
        cfg = restir.RenderConfig(method=method, spp=1, frames=max(frames_t) + 1, seed=2000 + k, max_depth=DEPTH,
                                  keep_frames=True)
        imgs.append(restir.render(sphere(), cfg).frame_images)
    imgs = np.stack(imgs).astype(np.float64)
    ref = np.full(imgs.shape[2:], EXACT)
    from scipy import stats as sps

    for t in frames_t:
        x = imgs[:, t]
        rep = RGBZTest(x.mean(0), x.var(0, ddof=1) / runs, ref, 0.0, tile=4, alpha=1e-3 / len(frames_t),
                       df=runs - 1, batches=x, rel_tol=ANALYTIC_REL_TOL,
                       skew=np.abs(np.nan_to_num(sps.skew(x, axis=0))), kurtosis=np.nan_to_num(sps.kurtosis(x, axis=0)))
        print("frame", t, f"MDB {100 * rep.mdb:.2f}%")
        assert rep.passed, f"frame {t}:\n{rep}"


LONG = {"spatial.neighbors": 8, "temporal.cap": 20.0}


def test_no_drift_over_many_frames():
    check_no_trend(*long_run_trend(seeds=8, frames=600, batch=50, scene=sphere(), method="restir-pt",
                                   max_depth=DEPTH, settings=LONG))


@pytest.mark.slow
def test_no_drift_over_many_frames_slow():
    check_no_trend(*long_run_trend(seeds=16, frames=5000, batch=100, scene=sphere(), method="restir-pt",
                                   max_depth=DEPTH, settings=LONG))
