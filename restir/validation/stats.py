"""Statistical machinery of the unbiasedness harness: chi-square on the sphere, z-tests, MDB.

False-failure rates: every test states its alpha. Chi-square tests use alpha = 1e-3 per test;
z-tests split alpha = 1e-3 per configuration between image, tile and pixel levels (Bonferroni),
as docs/validation.md#statistical-machinery describes.
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


def z_threshold(alpha: float, tests: int = 1, df: int | None = None) -> float:
    """Two-sided threshold with a Bonferroni split over `tests` (Student-t when df is given)."""
    q = alpha / (2 * tests)
    return float(sps.norm.isf(q) if df is None else sps.t.isf(q, df))


def mdb(z_crit: float, std_err: float, mean: float) -> float:
    """Minimum detectable relative bias at 80% power (docs/validation.md#minimum-detectable-bias)."""
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


class ZTestReport:
    """Image, tile and pixel z-tests of one channel of a noisy image against a reference
    (docs/validation.md#the-z-tests-image-tile-and-pixel).

    The family-wise false-failure rate alpha = 1e-3 is split 4e-4 (image), 3e-4 (tiles),
    3e-4 (pixels) with Bonferroni inside each level (Holm's step-down procedure rejects some
    hypothesis exactly when Bonferroni does, so for a pass/fail verdict the two coincide). Pixels of a path-traced image are
    independent, so the image and tile variances are sums of pixel variances.
    """

    def __init__(self, mean, var, ref, ref_var=0.0, tile=8, alpha=1e-3, df=None, skew=None, rel_tol=0.0,
                 kurtosis=None, abs_tol=0.0, batches=None, ref_batches=None):
        """rel_tol, abs_tol: an equivalence margin, |deviation| below rel_tol * |ref| + abs_tol
        counts as zero. Use it only where the reference itself is known to that precision
        (tessellated analytic scenes, ray offsets, float32 denormals), never to absorb noise.
        batches, ref_batches: (B, H, W) independent estimates (runs or independent frames) of
        each side. When given, tile and image variances are those of the batch-level tile and
        image means, which is right when pixels are correlated (spatial and temporal reuse);
        otherwise pixels are assumed independent and their variances are summed."""
        mean = np.asarray(mean, np.float64)
        var = np.asarray(var, np.float64)
        tile = max(1, min(tile, *mean.shape[:2]))  # an image smaller than a tile is one tile
        ref = np.broadcast_to(np.asarray(ref, np.float64), mean.shape)
        ref_var = np.broadcast_to(np.asarray(ref_var, np.float64), mean.shape)
        v = var + ref_var
        self.pixels = mean.size
        self.image_mean = float(mean.mean())
        self.image_ref = float(ref.mean())
        self.image_se = float(np.sqrt(v.sum()) / mean.size)
        agg_var = self._aggregate_variances(batches, tile) if batches is not None else None
        ref_agg = self._aggregate_variances(ref_batches, tile) if ref_batches is not None else None
        if agg_var is not None:
            img_v, tile_v = agg_var
            if ref_agg is not None:
                img_v, tile_v = img_v + ref_agg[0], tile_v + ref_agg[1]
            else:  # a noiseless or independent-pixel reference: its summed pixel variances
                img_v = img_v + float(ref_var.sum()) / mean.size ** 2
                tile_v = tile_v + tile_means(ref_var[..., None], ref_var[..., None], tile)[1][..., 0]
            self.image_se = float(np.sqrt(img_v))
        self.rel_tol = rel_tol
        self.abs_tol = abs_tol
        self.image_z = self._z(self.image_mean - self.image_ref, self.image_ref, self.image_se)
        tm, tv = tile_means(mean[..., None], v[..., None], tile)
        tr, _ = tile_means(ref[..., None], v[..., None], tile)
        if agg_var is not None:
            tv = tile_v[..., None]
        self.tile_z = self._z(tm - tr, tr, np.sqrt(tv)).ravel()
        # Skewness guard for tiles as for pixels (below): with batches, a tile whose per-batch
        # mean has |skew| > 1 on either side is not judged, and the tile level is inconclusive
        # when the median tile is (reuse spreads a firefly over its neighbours, so a tile's
        # batch means can stay as heavy-tailed as its pixels').
        self.tile_skew = 0.0
        if batches is not None:
            tsk = np.abs(self._tile_skewness(batches, tile))
            if ref_batches is not None:
                tsk = np.maximum(tsk, np.abs(self._tile_skewness(ref_batches, tile)))
            self.tile_skew = float(np.median(tsk))
            self.tiles_inconclusive = int(np.sum(tsk > 1.0))
            self.tile_z = np.where(tsk.ravel() > 1.0, 0.0, self.tile_z)
        else:
            self.tiles_inconclusive = 0
        self.tile_conclusive = self.tile_skew <= 1.0
        self.pixel_z = self._z(mean - ref, ref, np.sqrt(v))
        # Image and tile variances summed over many independent pixels have many degrees of
        # freedom (normal quantiles); estimated from B batch means they have B - 1 (t quantiles,
        # with the fewer batches of the two sides: conservative next to Welch-Satterthwaite).
        # Pixels use the t distribution of their own variance estimate's degrees of freedom.
        agg_df = None
        if agg_var is not None:
            agg_df = len(batches) - 1 if ref_agg is None else min(len(batches), len(ref_batches)) - 1
        self.image_crit = z_threshold(0.4 * alpha, 1, agg_df)
        self.tile_crit = z_threshold(0.3 * alpha, max(1, self.tile_z.size), agg_df)
        self.pixel_crit = z_threshold(0.3 * alpha, self.pixels, df)
        self.tail_crit = 3.0 if df is None else float(sps.t.isf(sps.norm.sf(3.0), df))
        # Skewness guard (docs/validation.md#heavy-tails-the-skew-and-kurtosis-guards), per pixel:
        # a pixel whose per-batch statistic has |skew| > 1 is inconclusive, not judged; the whole
        # pixel level is inconclusive when the median pixel is.
        self.skew = 0.0 if skew is None else float(np.median(np.abs(np.asarray(skew))))
        self.pixel_conclusive = self.skew <= 1.0
        # Degenerate pixels, also not judged: against a noisy reference, a pixel whose batches
        # never varied on one side (typically a rare event that side never saw, or saw equally
        # often, in every batch) and whose means differ has no estimate of that side's spread,
        # and its Welch z is meaningless. Such pixels still count in the tile and image means.
        unjudged = np.zeros(self.pixel_z.shape, bool)
        if np.any(ref_var > 0):
            unjudged = ((var == 0) | (ref_var == 0)) & (mean != ref)
        if skew is not None:
            unjudged |= np.abs(np.broadcast_to(np.asarray(skew, np.float64), self.pixel_z.shape)) > 1.0
        self.pixels_inconclusive = int(unjudged.sum())
        self.pixel_z = np.where(unjudged, 0.0, self.pixel_z)
        # The tail check looks for local biases (a bright corner, a dark glossy patch): a common
        # deviation of the whole image is the image-level test's to judge. Reuse that shares
        # samples across the image (Suffix ReSTIR's gather, wide spatial reuse) moves every pixel
        # of a run together, so a run-to-run shift of the whole image, well within the image
        # test's threshold, would push many pixels past |z| = 3 at once; the tail fraction is
        # therefore taken after taking out the image's relative deviation. A pixel counts only
        # when it deviates both from the reference and from the reference scaled by that common
        # deviation: noiseless pixels (emitters, a constant background; variance 0) match the
        # reference exactly and are not moved by shared reuse noise, so scaling their reference
        # would turn an exact match into an infinite z.
        scale = self.image_mean / self.image_ref if self.image_ref != 0 else 1.0
        local_z = np.minimum(np.abs(self.pixel_z), np.abs(self._z(mean - scale * ref, ref, np.sqrt(v))))
        local_z = np.where(unjudged, 0.0, local_z)
        self.tail = float(np.mean(local_z > self.tail_crit))
        # At most 1% beyond |z| > 3 (0.27% expected); on small images binomial noise alone can
        # exceed 1%, so the limit is at least the 1 - 1e-4 binomial quantile at twice 0.27%.
        self.tail_limit = max(0.01, float(sps.binom.isf(1e-4, self.pixels, 2 * 0.0027)) / self.pixels)
        # The tail-fraction check assumes near-normal pixel statistics; heavy-tailed batch means
        # (excess kurtosis well above 0) put more mass beyond 3 sigma without any bias.
        self.kurtosis = 0.0 if kurtosis is None else float(np.median(np.asarray(kurtosis)))
        self.tail_conclusive = self.pixel_conclusive and self.kurtosis <= 1.0
        self.mdb = mdb(self.image_crit, self.image_se, self.image_ref)

    @staticmethod
    def _batch_tiles(batches, tile):
        """(B, H, W) batches -> (B, H / tile, W / tile) tile means, in float64."""
        b = np.asarray(batches, np.float64)
        h, w = b.shape[1] - b.shape[1] % tile, b.shape[2] - b.shape[2] % tile
        return b[:, :h, :w].reshape(b.shape[0], h // tile, tile, w // tile, tile).mean(axis=(2, 4))

    @staticmethod
    def _tile_skewness(batches, tile):
        """Skewness over the B batches of each tile's mean."""
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.nan_to_num(sps.skew(ZTestReport._batch_tiles(batches, tile), axis=0))

    @staticmethod
    def _aggregate_variances(batches, tile):
        """Variance of the mean over B batches of the image mean and of each tile mean."""
        b = np.asarray(batches, np.float64)
        n = b.shape[0]
        tiles = ZTestReport._batch_tiles(b, tile)
        return float(b.mean(axis=(1, 2)).var(ddof=1) / n), tiles.var(axis=0, ddof=1) / n

    def _z(self, dev, ref, se):
        dev = np.sign(dev) * np.maximum(np.abs(dev) - self.rel_tol * np.abs(ref) - self.abs_tol, 0.0)
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(se > 0, dev / se, np.where(dev == 0, 0.0, np.inf))

    @property
    def passed(self) -> bool:
        pixels_ok = (np.all(np.abs(self.pixel_z) < self.pixel_crit) and (self.tail <= self.tail_limit or not self.tail_conclusive)) \
            or not self.pixel_conclusive
        tiles_ok = bool(np.all(np.abs(self.tile_z) < self.tile_crit)) or not self.tile_conclusive
        return abs(self.image_z) < self.image_crit and tiles_ok and bool(pixels_ok)

    def __str__(self) -> str:
        return (f"image {self.image_mean:.6g} vs {self.image_ref:.6g} (z={self.image_z:+.2f}, crit {self.image_crit:.2f}, "
                f"MDB {100 * self.mdb:.3f}%); max|z| tiles {np.abs(self.tile_z).max():.2f} (crit {self.tile_crit:.2f})"
                f"{f' ({self.tiles_inconclusive} skewed tiles not judged' + ('; tile level inconclusive)' if not self.tile_conclusive else ')') if self.tiles_inconclusive else ''}, "
                f"pixels {np.abs(self.pixel_z).max():.2f} (crit {self.pixel_crit:.2f}); tail fraction {self.tail:.4f} "
                f"(limit {self.tail_limit:.4f}); "
                f"median |skew| {self.skew:.2f} ({self.pixels_inconclusive} skewed or degenerate pixels not judged), "
                f"excess kurtosis {self.kurtosis:.2f}"
                f"{'' if self.pixel_conclusive else ' (pixel level inconclusive)'}"
                f"{' (tail check inconclusive)' if self.pixel_conclusive and not self.tail_conclusive else ''}")


class RGBZTest:
    """ZTestReport per colour channel, alpha split three ways (Bonferroni).

    Channels are tested separately because a path's channels are strongly correlated: the
    variance of their average is not the average of their variances over 3.
    """

    def __init__(self, mean, var, ref, ref_var=0.0, alpha=1e-3, skew=None, kurtosis=None, batches=None,
                 ref_batches=None, **kw):
        def ch(x, c):
            x = np.asarray(x, np.float64)
            return x[..., c] if x.ndim == 3 else x

        self.reports = [ZTestReport(ch(mean, c), ch(var, c), ch(ref, c), ch(ref_var, c), alpha=alpha / 3,
                                    skew=None if skew is None else ch(skew, c),
                                    kurtosis=None if kurtosis is None else ch(kurtosis, c),
                                    batches=None if batches is None else np.asarray(batches)[..., c],
                                    ref_batches=None if ref_batches is None else np.asarray(ref_batches)[..., c],
                                    **kw) for c in range(3)]

    @property
    def passed(self) -> bool:
        return all(r.passed for r in self.reports)

    @property
    def mdb(self) -> float:
        return max(r.mdb for r in self.reports)

    def zmap(self) -> np.ndarray:
        """Per-pixel z averaged over the channels as an RGB image: red where the estimate is
        above the reference, blue below, full intensity at |z| >= 5 (docs/validation.md#z-maps)."""
        z = np.mean([r.pixel_z for r in self.reports], axis=0)
        z = np.clip(np.nan_to_num(z) / 5.0, -1, 1)
        return np.stack([np.maximum(z, 0), np.zeros_like(z), np.maximum(-z, 0)], -1).astype(np.float32)

    def __str__(self) -> str:
        return "\n".join(f"  {c}: {r}" for c, r in zip("RGB", self.reports))
