"""The error-structure metrics of `restir compare` (restir/compare/structure.py) against cases with
known answers: white noise, noise constant over B x B blocks, the same noise in two frames; and
the pieces around them (the frame subset for the denoiser, the frame-time fit).

Tolerances are 5 standard errors of the estimate (computed from the case's own sampling
distribution), so each check has a false-failure probability below 1e-6 for any seed; the seeds
are fixed so the suite is deterministic. The smallest deviation each catches is stated beside it.
"""
import math

import numpy as np
import pytest

from restir.compare import equal_time, structure
from restir.compare.denoise import FrameSubset
from restir.compare.frames import FrameStats
from restir.compare.reference import Reference


def blocky(rng, shape, block):
    """Gaussian noise constant over aligned block x block squares: (..., H, W, C)."""
    *lead, h, w, c = shape
    coarse = rng.normal(size=(*lead, h // block, w // block, c))
    return np.repeat(np.repeat(coarse, block, axis=-3), block, axis=-2)


def test_correlation_factor_of_white_noise_is_one():
    rng = np.random.default_rng(1)
    e = rng.normal(size=(512, 512, 3))
    for b in structure.BLOCK_SIZES:
        # B^2 block-mean^2 / sigma^2 is chi^2_1 per block: the mean of n of them has SE sqrt(2 / n)
        n = (512 // b) ** 2 * 3
        assert structure.correlation_factor(e, b) == pytest.approx(1.0, abs=5 * np.sqrt(2 / n)), b  # B=16: 0.13


def test_correlation_factor_of_blocks_is_b_squared():
    rng = np.random.default_rng(2)
    for b in structure.BLOCK_SIZES:
        e = blocky(rng, (256, 256, 3), b)
        assert structure.correlation_factor(e, b) == pytest.approx(b * b, rel=1e-12)
        if b > 2:  # constant over the B x B block is constant over its sub-blocks
            assert structure.correlation_factor(e, b // 2) == pytest.approx(b * b / 4, rel=1e-12)
    # the part that does not fill a block is left out; an image smaller than a block has no value
    assert structure.correlation_factor(np.ones((10, 10, 3)), 4) == pytest.approx(16.0)
    assert np.isnan(structure.correlation_factor(np.ones((3, 3, 3)), 4))


def test_relative_error_squared_is_relmse():
    from restir.compare.metrics import relmse

    rng = np.random.default_rng(3)
    ref = rng.uniform(0, 2, size=(16, 16, 3))
    x = ref + rng.normal(size=ref.shape)
    assert np.mean(structure.relative_error(x, ref) ** 2) == pytest.approx(relmse(x, ref), rel=1e-12)


def test_temporal_correlation():
    rng = np.random.default_rng(4)
    e = rng.normal(size=(128, 128, 3))
    assert structure.temporal_correlation(e, e + 3.0) == pytest.approx(1.0, abs=1e-12)  # a shifted copy
    assert structure.temporal_correlation(e, 0.5 * e) == pytest.approx(1.0, abs=1e-12)
    assert structure.temporal_correlation(e, -e) == pytest.approx(-1.0, abs=1e-12)
    other = rng.normal(size=e.shape)
    assert abs(structure.temporal_correlation(e, other)) < 5 / np.sqrt(e.size)  # 0.017
    # half the error shared: correlation 1/2
    mixed = (e + other) / np.sqrt(2)
    assert structure.temporal_correlation(e, mixed) == pytest.approx(1 / np.sqrt(2), abs=5 / np.sqrt(e.size))


def _direct_ring(runs, r):
    """The prototype's definition, summed pair by pair: pixels standardised over the runs, the
    mean over overlapping pixels of sum_k z_a z_b / (K - 1) per offset, averaged over the ring."""
    k, h, w, c = runs.shape
    z = (runs - runs.mean(0)) / runs.std(0, ddof=1)
    values = []
    for dy in range(-r, r + 1):
        for dx in range(-r, r + 1):
            if max(abs(dy), abs(dx)) != r:
                continue
            a = z[:, max(0, -dy):h + min(0, -dy), max(0, -dx):w + min(0, -dx)]
            b = z[:, max(0, dy):h + min(0, dy), max(0, dx):w + min(0, dx)]
            values.append((a * b).sum(0).mean() / (k - 1))
    return np.mean(values)


def test_radial_correlation_of_white_noise_is_zero():
    rng = np.random.default_rng(5)
    runs = rng.normal(size=(16, 96, 96, 3)) + 2.0
    values, errors = structure.radial_correlation(runs)
    for r, v, se in zip(structure.RADII, values, errors):
        assert abs(v) < 5 * se, (r, v, se)  # se ~ 0.002-0.006: a correlation of 0.03 at r = 1 is caught
    assert values[0] == pytest.approx(_direct_ring(runs, 1), abs=1e-10)
    assert values[7] == pytest.approx(_direct_ring(runs, 8), abs=1e-10)


def test_radial_correlation_of_blocks_falls_to_zero_at_the_block_size():
    """Noise constant over B x B blocks: two pixels at offset (dy, dx) are in the same block (the
    same values in every run: sample correlation exactly 1) for a fraction (B - |dx|)(B - |dy|) / B^2
    of positions (in an image of n whole blocks, n (B - |d|) / (nB - |d|) per axis), otherwise
    independent (correlation 0 on average). So the ring mean falls from about 1 - 1/B at r = 1 to
    0 at r = B.

    The different-block pairs are not independent here: at one offset up to B^2 pixel pairs fall on
    the same pair of blocks (identical products), and a pair of blocks recurs at up to B offsets of
    a ring, so the ring mean's variance is at most B^3 times the one `radial_correlation` states for
    independent errors; the tolerance is 5 of those standard errors."""
    rng = np.random.default_rng(6)
    b, n = 4, 32
    runs = blocky(rng, (24, n * b, n * b, 3), b) + 1.0
    values, errors = structure.radial_correlation(runs)

    def same_block(d):
        return n * (b - abs(d)) / (n * b - abs(d)) if abs(d) < b else 0.0

    for r, v, se in zip(structure.RADII, values, errors):
        ring = [same_block(dy) * same_block(dx) for dy in range(-r, r + 1) for dx in range(-r, r + 1)
                if max(abs(dy), abs(dx)) == r]
        expected = np.mean(ring)
        tolerance = 5 * se * b ** 1.5  # 0.01-0.03
        assert v == pytest.approx(expected, abs=tolerance), (r, v, expected)
        if r >= b:
            assert expected == 0.0
    assert values[0] > values[1] > values[2] > 0.1  # falling with r
    assert values[2] == pytest.approx(_direct_ring(runs, 3), abs=1e-10)


def test_radial_correlation_leaves_out_constant_pixels():
    """A pixel equal in every run (a black background) has no correlation: pairs with it are left
    out, not counted as 0 (the ring mean of perfectly correlated runs stays 1)."""
    rng = np.random.default_rng(7)
    base = rng.normal(size=(8, 32, 32, 1))
    runs = np.repeat(base[:, :1, :1], 32, axis=1).repeat(32, axis=2)  # every pixel the same value per run
    runs[:, :8] = 0.0  # a constant strip
    values, _ = structure.radial_correlation(runs, radii=(1, 4))
    assert values == pytest.approx([1.0, 1.0], abs=1e-9)
    with pytest.raises(ValueError, match="at least 3"):
        structure.radial_correlation(runs[:2])
    assert np.isnan(structure.radial_correlation(runs, radii=(40,))[0][0])


def test_frame_stats_measure_after_the_warmup():
    """FrameStats (what compare runs) gives the factor of blocky frames, the temporal correlation
    of frames sharing their error, and leaves the warm-up frames out."""
    rng = np.random.default_rng(8)
    ref = Reference(np.ones((64, 64, 3)), "ones")
    fs = FrameStats(ref, warmup=2)
    fs.add(np.ones((64, 64, 3)) + 50 * rng.normal(size=(64, 64, 3)))  # warm-up: white, large
    fs.add(np.ones((64, 64, 3)))  # warm-up: no error at all
    shared = blocky(rng, (64, 64, 3), 8)
    for k in range(4):
        fs.add(1.0 + shared + 1e-9 * k)
    s = fs.structure()
    assert s["correlation_factor"]["8"] == pytest.approx(64.0, rel=1e-6)
    assert s["correlation_factor"]["2"] == pytest.approx(4.0, rel=1e-6)
    assert s["temporal_correlation"] == pytest.approx(1.0, abs=1e-9)
    assert len(fs.temporal) == 3 and fs.denoise_frames()[0] == [2, 3, 4, 5]


def test_frame_subset_is_evenly_spaced_and_bounded():
    for n in (1, 8, 16, 17, 100, 1000):
        s = FrameSubset(target=8)
        for i in range(n):
            s.offer(i + 4, np.full((1, 1, 3), i))
        if n <= 16:
            assert s.indices == [i + 4 for i in range(n)]
        else:
            assert 9 <= len(s.indices) <= 16, (n, s.indices)
            steps = np.diff(s.indices)
            assert np.all(steps == steps[0]) and s.indices[0] == 4
        assert [float(f[0, 0, 0]) for f in s.frames] == [i - 4.0 for i in s.indices]


def test_frame_time_fit_accounts_for_the_fixed_cost(monkeypatch):
    """A path tracer whose frame costs 12 ms + 3 ms per spp: the fit recovers both, and a 60-ms
    frame is worth 16 spp (t / t_1spp would give 4)."""
    probes = []

    def fake_ms(scene, config):
        probes.append(config.spp)
        return 12.0 + 3.0 * config.spp

    monkeypatch.setattr(equal_time, "_frame_ms", fake_ms)
    from restir.config import RenderConfig

    fit = equal_time.fit_frame_time(None, RenderConfig(), longest_ms=60.0)
    assert probes == [1, 4]  # 1 spp, then near the longest frame's time in 1-spp frames
    assert (fit.fixed_ms, fit.per_spp_ms) == pytest.approx((12.0, 3.0))
    assert fit.spp_at(60.0) == pytest.approx(16.0) and fit.spp_at(15.0) == 1.0 and fit.spp_at(1.0) == 1.0
    # the whole spp on both sides of a frame's worth: 16.5 ms is 1.5 samples
    assert fit.bracket(16.5) == (1, 2) and fit.bracket(60.0) == (16,) and fit.bracket(1.0) == (1,)
    assert fit.to_dict()["probes"] == [{"spp": 1, "ms": 15.0}, {"spp": 4, "ms": 24.0}]


def test_reference_own_relmse():
    """Blocks of known spread: 16 independent estimates with standard deviation 0.2 around 1 give
    a mean whose variance is 0.04 / 16, so relMSE 0.0025 / 1.01 (the mean's own scatter, 5%,
    shifts the denominator by under 1%); an exact reference has none."""
    rng = np.random.default_rng(9)
    blocks = 1.0 + 0.2 * rng.normal(size=(16, 64, 64, 3))
    ref = Reference(blocks.mean(axis=0), "blocks", blocks)
    # the variance estimate from 16 blocks has relative SE sqrt(2 / 15) per pixel, over 12288 values
    assert ref.own_relmse() == pytest.approx(0.0025 / 1.01, rel=0.05)
    assert Reference(np.ones((4, 4, 3)), "exact").own_relmse() is None


def test_headline_interpolates_the_path_tracer_between_whole_spp():
    """At equal time a frame worth 1.5 path-tracer samples is compared with the path tracer's
    errors at 1 and 2 spp interpolated log-log (errors 0.04 at 1 spp and 0.02 at 2 give
    0.04 * 0.5 ** log2(1.5) at 1.5); a frame worth a whole spp is compared with that one alone."""
    from types import SimpleNamespace

    from restir.compare.headline import headline

    def result(label, method, spp, ms, raw, den, acc, of=()):
        metrics = {"ms_per_frame": ms, "relmse_frame": raw, "relmse_denoised_frame": den, "relmse_accumulated": acc}
        return SimpleNamespace(label=label, method=method, spp=spp, metrics=metrics, frame_time_of=list(of))

    pt1 = result("pt", "pt", 1, 30.0, 4.0, 0.04, 1.0, of=["restir-pt"])
    pt2 = result("pt:spp=2", "pt", 2, 60.0, 2.0, 0.02, 0.9, of=["restir-pt"])
    pt3 = result("pt:spp=3", "pt", 3, 90.0, 1.3, 0.015, 0.8, of=["restir-di"])
    rpt = result("restir-pt", "restir-pt", 1, 45.0, 1.0, 0.025, 0.5)
    rdi = result("restir-di", "restir-di", 1, 90.0, 1.0, 0.01, 0.4)
    comparison = SimpleNamespace(methods=[pt1, rpt, rdi, pt2, pt3], budget="time: 1 s",
                                 frame_time_fit={"spp_of": {"restir-pt": 1.5, "restir-di": 3.0}})
    h_pt, h_di = headline(comparison)
    t = math.log(1.5) / math.log(2.0)
    assert h_pt["baseline_spp"] == 1.5 and h_pt["basis"] == "equal frame time"
    assert h_pt["raw_frame"] == pytest.approx(4.0 * 0.5 ** t / 1.0)
    assert h_pt["denoised_frame"] == pytest.approx(0.04 * 0.5 ** t / 0.025)
    assert h_pt["accumulated"] == pytest.approx(math.exp((1 - t) * math.log(1.0) + t * math.log(0.9)) / 0.5)
    assert h_pt["ms_per_frame"] == [45.0, pytest.approx(45.0)]
    assert "against the path tracer at 1.50 spp, pt and pt:spp=2 interpolated (equal frame time" in h_pt["text"]
    assert h_di["baseline"] == "pt:spp=3" and h_di["denoised_frame"] == pytest.approx(1.5)
    assert h_di["text"].startswith("restir-di against pt:spp=3 (equal frame time")
