"""The harness's pytest helper: a failing check leaves a z-map image, a passing one nothing."""
import numpy as np
import pytest

from restir.image_io import read_image
from restir.validation import assert_matches


class Batches:
    """K independent normal batch estimates of an image (the interface the helper reads)."""

    def __init__(self, mean, k=32, sigma=0.01, seed=0):
        rng = np.random.default_rng(seed)
        self.batches = mean + sigma * rng.standard_normal((k,) + mean.shape)
        self.image = self.batches.mean(0)
        self.batch_variance_of_mean = self.batches.var(0, ddof=1) / k
        self.batch_skewness = np.zeros(mean.shape)
        self.batch_excess_kurtosis = np.zeros(mean.shape)
        self.frames = k


def test_failing_check_writes_a_zmap(tmp_path, monkeypatch):
    monkeypatch.setenv("RESTIR_ZMAP_DIR", str(tmp_path))
    ref = np.full((16, 16, 3), 0.5)
    biased = ref.copy()
    biased[:8, :8] *= 1.2  # a bright corner: the z-map must show it red, the rest dark
    with pytest.raises(AssertionError, match="z-map: ") as err:
        assert_matches(Batches(biased), ref)
    path = str(err.value).rsplit("z-map: ", 1)[1].strip()
    assert path.startswith(str(tmp_path)) and "test_failing_check_writes_a_zmap" in path
    z = read_image(path)
    assert z[:8, :8, 0].mean() > 0.9 and z[8:, 8:, 0].mean() < 0.5


def test_passing_check_writes_nothing(tmp_path, monkeypatch):
    monkeypatch.setenv("RESTIR_ZMAP_DIR", str(tmp_path))
    ref = np.full((16, 16, 3), 0.5)
    rep = assert_matches(Batches(ref, seed=1), ref)
    assert rep.passed and not list(tmp_path.iterdir())


def test_degenerate_pixel_is_not_judged():
    """A rare event that one side never saw in any batch (all batches 0 at a pixel, against a
    noisy reference there) gives no estimate of that side's spread: the pixel is left to the
    tile and image levels instead of failing on a meaningless z."""
    from restir.validation import RGBZTest

    ref = Batches(np.full((16, 16, 3), 0.5), seed=2)
    est = Batches(np.full((16, 16, 3), 0.5), seed=3)
    est.batches[:, 3, 3] = 0.0  # never saw the rare light of pixel (3, 3)
    est.image, est.batch_variance_of_mean = est.batches.mean(0), est.batches.var(0, ddof=1) / est.frames
    ref.batches[:, 3, 3] = 0.002 * (1 + ref.batches[:, 3, 3])  # rare and small, but seen
    ref.image, ref.batch_variance_of_mean = ref.batches.mean(0), ref.batches.var(0, ddof=1) / ref.frames
    rep = RGBZTest(est.image, est.batch_variance_of_mean, ref.image, ref.batch_variance_of_mean, df=31,
                   batches=est.batches, ref_batches=ref.batches)
    assert rep.passed and all(r.pixels_inconclusive == 1 for r in rep.reports)


def test_harness_refuses_fault_injection():
    """The harness tests the unbiased build: a debug.mutation setting must be asked for."""
    import restir
    from restir.validation import IndependentRuns

    scene = restir.load_scene("builtin:cornell-box")
    cfg = restir.RenderConfig(method="restir-di", width=8, height=8, settings={"debug.mutation": "drop_empty_neighbors"})
    with pytest.raises(AssertionError, match="fault injection"):
        IndependentRuns(scene, cfg, 2)
    assert IndependentRuns(scene, cfg, 2, allow_mutation=True).counters["nonfinite_weights"] == 0


def test_skewed_tiles_are_not_judged():
    """The skew guard at the tile level
    (docs/validation.md#heavy-tails-the-skew-and-kurtosis-guards): with heavy-tailed batch means (lognormal,
    sigma 2: tile skew far above 1) no tile is judged and the tile level is inconclusive, while
    normal batches are judged (and a 10% bias in one tile of them fails)."""
    from restir.validation.stats import ZTestReport

    rng = np.random.default_rng(4)
    heavy_a, heavy_b = rng.lognormal(0, 2.0, (2, 128, 32, 32))
    r = ZTestReport(heavy_a.mean(0), heavy_a.var(0, ddof=1) / 128, heavy_b.mean(0), heavy_b.var(0, ddof=1) / 128,
                    batches=heavy_a, ref_batches=heavy_b)
    assert not r.tile_conclusive and r.tiles_inconclusive == 16
    a, b = rng.normal(1.0, 0.1, (2, 128, 32, 32))
    a[:, :8, :8] *= 1.1
    r = ZTestReport(a.mean(0), a.var(0, ddof=1) / 128, b.mean(0), b.var(0, ddof=1) / 128, batches=a, ref_batches=b)
    assert r.tile_conclusive and r.tiles_inconclusive == 0 and not r.passed and np.abs(r.tile_z).max() > r.tile_crit


def test_tail_check_looks_for_local_biases():
    """The tail fraction (|z| > 3) is taken after the image's common relative deviation is taken
    out: a whole-image shift of 2.5 standard errors per pixel (the image test's to judge: here
    well inside its threshold, the pixels being correlated) passes it, while 6% of the pixels
    biased by 4 standard errors fail it."""
    from restir.validation.stats import ZTestReport

    rng = np.random.default_rng(8)
    k = 64
    common = rng.normal(0, 1, (k, 1, 1))  # one shift per run, shared by every pixel
    a = 1.0 + 0.01 * (0.3 * rng.normal(size=(k, 32, 32)) + common)
    shifted = a - a.mean() + 1.0 - 2.5 * a.std(0, ddof=1).mean() / np.sqrt(k)
    r = ZTestReport(shifted.mean(0), shifted.var(0, ddof=1) / k, 1.0, 0.0, batches=shifted, df=k - 1)
    assert r.tail <= r.tail_limit and r.passed
    b = 1.0 + 0.01 * rng.normal(size=(k, 32, 32))
    b[:, :8, :8] += 4 * 0.01 / np.sqrt(k)
    r = ZTestReport(b.mean(0), b.var(0, ddof=1) / k, 1.0, 0.0, batches=b, df=k - 1)
    assert r.tail > r.tail_limit and not r.passed


def test_tail_check_keeps_noiseless_pixels_exact():
    """Noiseless pixels (an emitter seen directly, a constant background: variance 0, equal to
    the reference) stay out of the tail when the noisy rest of the image carries a small common
    deviation; scaling their reference by it would give them an infinite z (the regression that
    failed 39 fast-tier tests: every emitter and background pixel counted in the tail)."""
    from restir.validation.stats import ZTestReport

    rng = np.random.default_rng(9)
    k = 64
    common = rng.normal(0, 1, (k, 1, 1))  # one shift per run, shared by every noisy pixel
    a = 1.0 + 0.01 * (0.3 * rng.normal(size=(k, 32, 32)) + common)
    a = a - a.mean() + 1.0 - 2.5 * a.std(0, ddof=1).mean() / np.sqrt(k)
    a[:, :, :8] = 5.0  # a quarter of the image noiseless and exact
    ref = np.where(np.arange(32) < 8, 5.0, 1.0)[None, :].repeat(32, 0)
    r = ZTestReport(a.mean(0), a.var(0, ddof=1) / k, ref, 0.0, batches=a, df=k - 1)
    assert r.tail <= r.tail_limit and r.passed
