"""Level 7: bitwise repeatability per (seed, frame), independent streams across seeds and frames,
and independence from how a CPU launch is sliced (R1, R2). Statistical tests: alpha = 1e-3 each."""
import numpy as np
import pytest
from scipy import stats as sps

import restir


ALPHA = 1e-3


def render(slices, seed=3, device="cpu", frames=2, tracer="auto"):
    scene = restir.load_scene("builtin:cornell-box-glossy", width=24, height=20)
    cfg = restir.RenderConfig(spp=3, frames=frames, seed=seed, device=device, max_depth=6, slices=slices, tracer=tracer)
    return restir.render(scene, cfg).image


def frame_images(seed, frames=2, device="cpu", spp=3, width=24, height=20, slices=2):
    """The per-frame images (F, H, W, 3) of a path-traced render."""
    scene = restir.load_scene("builtin:cornell-box-glossy", width=width, height=height)
    cfg = restir.RenderConfig(spp=spp, frames=frames, seed=seed, device=device, max_depth=6, slices=slices,
                              keep_frames=True)
    return restir.render(scene, cfg).frame_images


def test_same_seed_is_bitwise_identical():
    a, b = render(2), render(2)
    assert np.array_equal(a, b)


def test_same_seed_and_frame_is_bitwise_identical():
    """A path-traced frame is a function of (seed, frame index) only: rendering it again, or as
    part of a longer run, reproduces it bit for bit."""
    a, b = frame_images(3, frames=2), frame_images(3, frames=2)
    assert np.array_equal(a, b)
    assert np.array_equal(frame_images(3, frames=1)[0], a[0])  # frame 0 alone = frame 0 of two
    assert np.array_equal(frame_images(3, frames=3)[:2], a)    # a third frame changes neither


@pytest.mark.parametrize("tracer", ["auto", "warp"])
@pytest.mark.parametrize("slices", [1, 3, 7, 480])
def test_result_is_independent_of_slicing(slices, tracer):
    assert np.array_equal(render(2, tracer=tracer), render(slices, tracer=tracer))


# Each method at small settings that exercise all its passes (reuse of every kind, two frames).
METHOD_CONFIGS = {
    "pt": ("builtin:cornell-box-glossy", 4, {}),
    "restir-di": ("builtin:cornell-box-glossy", 2, {"candidates": 2, "spatial.rounds": 2, "spatial.neighbors": 4}),
    "restir-pt": ("builtin:indirect-room", 4, {"spatial.rounds": 2, "spatial.neighbors": 4}),
    "suffix-restir": ("builtin:indirect-room", 4, {"suffix.spatial.rounds": 2, "gather.suffixes": 3}),
}


def render_method(method, device, seed=3):
    spec, max_depth, settings = METHOD_CONFIGS[method]
    scene = restir.load_scene(spec, width=24, height=20)
    cfg = restir.RenderConfig(method=method, spp=2, frames=2, seed=seed, device=device, max_depth=max_depth,
                              settings=settings)
    return restir.render(scene, cfg).image


@pytest.mark.gpu
@pytest.mark.parametrize("method", list(METHOD_CONFIGS))
def test_each_method_is_bitwise_repeatable_on_the_device(method, device):
    """R1 on the device under test (the GPU check runs it on CUDA): the same seed twice gives
    bitwise the same image. On a GPU a kernel that reads what another thread of the same launch
    writes, or that sums floats with atomics in thread order, would differ between runs."""
    a, b = render_method(method, device), render_method(method, device)
    assert np.isfinite(a).all() and a.max() > 0
    assert np.array_equal(a, b)
    assert not np.array_equal(a, render_method(method, device, seed=4))  # the seed is used


def test_seeds_and_frames_give_independent_streams():
    """Every (seed, frame) pair has its own random stream: all eight images of seeds 3..6 x
    frames 0, 1 differ, and differences of disjoint pairs are independent.

    Independence is tested with an exact sign test: the difference A - B of two independent
    renders of one pixel is symmetric about 0, so when a second such difference C - D is
    independent of it, their signs agree with probability 1/2, independently over pixels
    (pixels that render the same value in both pairs are left out). Pearson's correlation would
    be dominated by the few pixels with fireflies, and its 1/sqrt(n) spread does not hold.
    Binomial test per comparison, alpha = 1e-3 split over the three comparisons; with about
    12,000 pixels a sign-agreement rate of 0.53 instead of 0.5 is caught."""
    imgs = {(s, f): im for s in (3, 4, 5, 6) for f, im in enumerate(frame_images(s, frames=2, spp=1, width=128,
                                                                                 height=96))}
    keys = list(imgs)
    for i, k in enumerate(keys):
        for k2 in keys[i + 1:]:
            assert not np.array_equal(imgs[k], imgs[k2]), f"(seed, frame) {k} and {k2} render the same image"

    def diff(k, k2):  # one value per pixel (the channels of a pixel correlate)
        return (imgs[k].astype(np.float64) - imgs[k2]).sum(-1).ravel()

    pairs = {
        "frames": (diff((3, 0), (3, 1)), diff((4, 0), (4, 1))),
        "seeds": (diff((3, 0), (4, 0)), diff((5, 0), (6, 0))),
        "seed + frame": (diff((3, 1), (4, 0)), diff((5, 1), (6, 0))),  # a stream (s, f + 1) = (s + 1, f) shows here
    }
    for name, (x, y) in pairs.items():
        judged = (x != 0) & (y != 0)
        n = int(judged.sum())
        agree = int((np.sign(x[judged]) == np.sign(y[judged])).sum())
        assert n > 10_000
        p = sps.binomtest(agree, n, 0.5).pvalue
        assert p > ALPHA / len(pairs), f"{name}: signs agree in {agree} of {n} pixels (p={p:.2e})"


def assert_same_mean(a, b, alpha=ALPHA):
    """Welch's t-test, per channel, of the image means of two sets of independent frames
    (F, H, W, 3): path-traced frames of distinct (seed, frame) pairs are independent
    estimates of the same image. alpha is split over the three channels (Bonferroni)."""
    ma, mb = a.mean(axis=(1, 2)).astype(np.float64), b.mean(axis=(1, 2)).astype(np.float64)
    for c in range(3):
        t, p = sps.ttest_ind(ma[:, c], mb[:, c], equal_var=False)
        assert p > alpha / 3, (f"channel {c}: image means {ma[:, c].mean():.5g} vs {mb[:, c].mean():.5g} "
                               f"(t={t:.2f}, p={p:.2e})")


# 64 independent frames of 32x32 pixels x 16 spp per side: the relative standard error of the
# difference of the two image means is 0.6-0.8% per channel, so with the t-test's critical
# value of about 3.7 a bias of 3-4% is caught with 80% power (a 5% bias fails reliably).
STAT_FRAMES, STAT_SPP, STAT_SIZE = 64, 16, 32


def stat_frames(seed, device):
    return frame_images(seed, frames=STAT_FRAMES, device=device, spp=STAT_SPP, width=STAT_SIZE, height=STAT_SIZE,
                        slices=None)


def test_independent_seeds_agree_statistically():
    """Two seeds estimate the same image: their image means pass a t-test (alpha = 1e-3)."""
    assert_same_mean(stat_frames(3, "cpu"), stat_frames(4, "cpu"))


def test_cuda_matches_cpu_statistically(device):
    """CPU and CUDA renders, with different seeds so that they are independent, estimate the
    same image: their image means pass a t-test (alpha = 1e-3)."""
    if device == "cpu":
        pytest.skip("run with --device cuda")
    assert_same_mean(stat_frames(3, "cpu"), stat_frames(4, device))


def render_di(slices, mutation="none", reverse=False):
    scene = restir.load_scene("builtin:cornell-box-glossy", width=24, height=20)
    cfg = restir.RenderConfig(method="restir-di", spp=2, frames=2, seed=3, slices=slices, debug_reverse_launch=reverse,
                              settings={"candidates": 2, "spatial.rounds": 2, "spatial.neighbors": 4,
                                        "debug.mutation": mutation})
    return restir.render(scene, cfg).image


@pytest.mark.parametrize("slices", [1, 3, 7, 480])
def test_restir_di_is_independent_of_slicing(slices):
    """R2: with ping-pong buffers no pixel reads another pixel's output of the same pass."""
    assert np.array_equal(render_di(2), render_di(slices))
    assert np.array_equal(render_di(2), render_di(slices, reverse=True))  # and of the processing order


def test_in_place_spatial_output_is_caught():
    """Mutation P5/S1: writing the spatial output into the buffer the pass reads makes the
    result depend on the order pixels are processed: forward (one slice) and reversed slices
    differ, deterministically (a threaded launch would show it only when threads interleave)."""
    forward = render_di(1, "spatial_in_place")
    assert not np.array_equal(forward, render_di(7, "spatial_in_place", reverse=True))


def render_pt(slices, mutation="none", reverse=False, reciprocal=False):
    scene = restir.load_scene("builtin:indirect-room", width=24, height=20)
    cfg = restir.RenderConfig(method="restir-pt", spp=2, frames=2, seed=3, slices=slices, debug_reverse_launch=reverse,
                              max_depth=4, settings={"spatial.rounds": 2, "spatial.neighbors": 4,
                                                     "spatial.reciprocal": reciprocal, "debug.mutation": mutation})
    return restir.render(scene, cfg).image


@pytest.mark.parametrize("reciprocal", [False, True])
@pytest.mark.parametrize("slices", [1, 7, 480])
def test_restir_pt_is_independent_of_slicing(slices, reciprocal):
    """R2 for ReSTIR PT (its DI component included): ping-pong everywhere. The reciprocal spatial
    pass writes two pixels per thread (a pair's), each of which no other thread of the launch
    reads or writes. (render_pt pins independent neighbours by default: the race mutant below is
    the independent pass writing its own input.)"""
    assert np.array_equal(render_pt(2, reciprocal=reciprocal), render_pt(slices, reciprocal=reciprocal))
    assert np.array_equal(render_pt(2, reciprocal=reciprocal), render_pt(slices, reverse=True, reciprocal=reciprocal))


def test_restir_pt_in_place_spatial_output_is_caught():
    """Mutation: ReSTIR PT's spatial pass writing the buffer it reads (see above)."""
    assert not np.array_equal(render_pt(1, "spatial_in_place"), render_pt(7, "spatial_in_place", reverse=True))


def render_sr(slices, mutation="none", reverse=False):
    scene = restir.load_scene("builtin:indirect-room", width=24, height=20)
    cfg = restir.RenderConfig(method="suffix-restir", spp=2, frames=2, seed=3, slices=slices,
                              debug_reverse_launch=reverse, max_depth=4,
                              settings={"suffix.spatial.rounds": 2, "suffix.spatial.neighbors": 4,
                                        "gather.suffixes": 3, "debug.mutation": mutation})
    return restir.render(scene, cfg).image


@pytest.mark.parametrize("slices", [1, 7, 480])
def test_suffix_restir_is_independent_of_slicing(slices):
    """R2 for Suffix ReSTIR (prefix, suffix and gather passes, the search structure, ReSTIR DI)."""
    assert np.array_equal(render_sr(2), render_sr(slices))
    assert np.array_equal(render_sr(2), render_sr(slices, reverse=True))


def test_suffix_restir_in_place_spatial_output_is_caught():
    """Mutation: the suffix spatial pass writing the buffer it reads (see above)."""
    assert not np.array_equal(render_sr(1, "spatial_in_place"), render_sr(7, "spatial_in_place", reverse=True))
