"""Suffix ReSTIR over frames and parameters (I6 of docs/validation.md#level-4-invariance-tests;
docs/validation.md#level-5-long-run-stability), on the emissive-cap sphere
(exact reference), with the harness of the ReSTIR PT long tests (test_restir_pt_long.py):

- I6: image means over independent runs for the gather's prefixes N, suffixes M, search radius
  multiplier and the minimum prefix length; a weighted regression on the parameter must have
  |slope / SE| < 3.5, and every configuration passes the exact z-test (N and M in the fast tier,
  radius and prefix length in the slow one).
- L1: frame t alone is unbiased for t in {0, 1, 2, 4, 8, 15} (Bonferroni over the frames).
- L2: the long run with everything on (the seed report's bright spots): no trend in the batch
  means, no growing maxima, nothing non-finite. Fast: 8 seeds x 300 frames; slow: 16 x 5000.
"""
import pytest

from tests.helpers import SPHERE_DEPTH as DEPTH
from tests.helpers import check_every_frame, check_flat, check_no_trend, long_run_trend
from tests.helpers import sphere_cap as sphere

METHOD = "suffix-restir"


def test_invariance_in_prefixes():
    check_flat([1, 2, 4, 8], lambda n: {"gather.prefixes": n}, METHOD)


@pytest.mark.slow  # 71 s; the invariance in prefixes stays in the fast tier
def test_invariance_in_suffixes():
    check_flat([1, 2, 4, 8], lambda m: {"gather.suffixes": m}, METHOD)


@pytest.mark.slow
def test_invariance_in_search_radius():
    check_flat([0.5, 1.0, 2.0, 4.0], lambda r: {"gather.radius": r, "gather.suffixes": 2}, METHOD)


@pytest.mark.slow
def test_invariance_in_prefix_length():
    check_flat([1, 2, 3], lambda p: {"prefix.min_length": p}, METHOD)


def test_every_frame_is_unbiased():
    check_every_frame(METHOD)


def test_no_drift_over_many_frames():
    check_no_trend(*long_run_trend(seeds=8, frames=300, batch=50, scene=sphere(), method=METHOD, max_depth=DEPTH,
                                   settings={"gather.suffixes": 4}))


@pytest.mark.slow
def test_no_drift_over_many_frames_slow():
    check_no_trend(*long_run_trend(seeds=16, frames=5000, batch=100, scene=sphere(), method=METHOD, max_depth=DEPTH,
                                   settings={"gather.suffixes": 4}))
