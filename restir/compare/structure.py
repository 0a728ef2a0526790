"""The structure of a method's error: how much of it a denoiser can see as noise.

A denoiser averages neighbouring pixels. Independent pixel errors shrink under that average as
1 / (pixels averaged); errors shared by neighbours (the blotches of spatiotemporal reuse) do not.
Three measures of that sharing, each 0 or 1 for independent errors (docs/guide/compare.md has the
derivations):

- `correlation_factor(e, B)`: B^2 * mean(block-mean(e)^2) / mean(e^2) over aligned B x B blocks,
  e the relative error of one frame. The mean squared error left after averaging each B x B block
  is mean(e^2) * factor / B^2: 1 for independent errors (the average of B^2 of them has 1/B^2
  of their variance), B^2 for errors constant over each block (averaging removes nothing).
- `radial_correlation(runs, radii)`: from K independent runs at one frame index, each pixel
  standardised over the runs; the Pearson correlation of pixel p with pixel p + (dy, dx), averaged
  over every p and over the square ring max(|dy|, |dx|) = r. As the official conditional-ReSTIR
  prototype measures it (its ComputeCovariance.py); here the sums over all pixel pairs at an
  offset are computed for every offset at once by FFT, and divided by the pairs that exist at
  that offset.
- `temporal_correlation(e_prev, e)`: the Pearson correlation over pixels of consecutive frames'
  relative errors; what makes the accumulated error fall slower than 1 / frames.

The relative error is e = (x - ref) / sqrt(ref^2 + 0.01), per channel: its mean square is the
relMSE (metrics.relmse). A noisy reference adds its own error, the same in every frame, to every
e; with the reference at R spp and frames at s spp that is about s / R of a frame's error
variance (1024-spp reference, 1-spp frames: a temporal correlation of about 0.001).
"""
import numpy as np

from .metrics import EPSILON

BLOCK_SIZES = (2, 4, 8, 16)
RADII = tuple(range(1, 17))
TABLE_RADII = (1, 4, 8, 16)  # the radii of the terminal table and the benchmarks' tables


def relative_error(image, reference) -> np.ndarray:
    """(x - ref) / sqrt(ref^2 + 0.01) per pixel and channel (float64)."""
    x = np.asarray(image, np.float64)
    y = np.asarray(reference, np.float64)
    return (x - y) / np.sqrt(y * y + EPSILON)


def correlation_factor(errors, block: int) -> float:
    """B^2 * mean(block-mean(e)^2) / mean(e^2) of one frame's errors (H, W, C), over the aligned
    B x B blocks that fit (the last rows and columns that do not fill a block are left out).
    NaN when the errors are all 0 or the image is smaller than one block."""
    e = np.asarray(errors, np.float64)
    h, w = (e.shape[0] // block) * block, (e.shape[1] // block) * block
    if h == 0 or w == 0:
        return float("nan")
    e = e[:h, :w]
    means = e.reshape(h // block, block, w // block, block, -1).mean(axis=(1, 3))
    denom = np.mean(e * e)
    return float(block * block * np.mean(means * means) / denom) if denom > 0 else float("nan")


def temporal_correlation(previous, current) -> float:
    """Pearson correlation over pixels and channels of two frames' errors; NaN if either is
    constant."""
    a = np.asarray(previous, np.float64).ravel()
    b = np.asarray(current, np.float64).ravel()
    a = a - a.mean()
    b = b - b.mean()
    # sums of products, not np.dot: a BLAS call leaves OpenBLAS's threads spinning on the cores
    # for a while after it returns, which slowed the next frame of a timed run by 60% (measured)
    denom = np.sqrt(np.sum(a * a) * np.sum(b * b))
    return float(np.sum(a * b) / denom) if denom > 0 else float("nan")


def _autocorrelation(fields, height, width):
    """sum over k and over every pixel p of f_k(p) * f_k(p + d), for every offset d, by FFT:
    (2H - 1, 2W - 1) array, offset (dy, dx) at [H - 1 + dy, W - 1 + dx]. fields: (K, H, W)."""
    shape = (2 * height - 1, 2 * width - 1)
    spectrum = np.fft.rfft2(fields, s=shape)
    power = (spectrum * np.conj(spectrum)).sum(axis=0)
    corr = np.fft.irfft2(power, s=shape)
    # index 0 holds offset 0; negative offsets wrap to the end: move offset 0 to the centre
    return np.roll(corr, (height - 1, width - 1), axis=(0, 1))


def radial_correlation(runs, radii=RADII):
    """Radial correlation of K independent runs (K, H, W, C) at the given ring radii.

    Returns (values, standard_errors), one per radius. A pixel whose K values are all equal (a
    black background, say) has no correlation and is left out of every pair it is in, as in the
    prototype. The standard error is the one the value has when the errors are independent
    (each pair's Pearson estimate has variance 1 / (K - 1) then, and distinct pixel pairs are
    uncorrelated), counting the channels of a pixel as one (they share their paths, so they may
    be fully correlated: conservative when they are not) and the offsets d and -d as one (the
    same pairs): a value many of them away from 0 is correlation, not chance. Radii that reach
    past the image are NaN.
    """
    x = np.asarray(runs, np.float64)
    if x.ndim == 3:
        x = x[..., None]
    k, h, w, c = x.shape
    if k < 3:
        raise ValueError("radial correlation needs at least 3 independent runs")
    std = x.std(axis=0, ddof=1)
    valid = std > 0
    z = np.where(valid, (x - x.mean(axis=0)) / np.where(valid, std, 1.0), 0.0)
    # per channel, runs summed: the sum over pixel pairs of z_a z_b; the pairs that exist (both
    # pixels valid) from the same transform of the validity mask
    sums = sum(_autocorrelation(z[..., ch], h, w) for ch in range(c))
    pairs = sum(_autocorrelation(valid[None, ..., ch].astype(np.float64), h, w) for ch in range(c))
    pairs = np.rint(pairs)
    values, errors = [], []
    for r in radii:
        if r >= h or r >= w:
            values.append(float("nan"))
            errors.append(float("nan"))
            continue
        ring = np.zeros((2 * r + 1, 2 * r + 1), bool)
        ring[[0, -1], :] = True
        ring[:, [0, -1]] = True
        s = sums[h - 1 - r:h + r, w - 1 - r:w + r][ring]
        n = pairs[h - 1 - r:h + r, w - 1 - r:w + r][ring]
        ok = n > 0
        values.append(float(np.mean(s[ok] / ((k - 1) * n[ok]))) if ok.any() else float("nan"))
        # an offset's mean over its n / c pixel pairs (channels as one) has variance c / ((K - 1) n);
        # d and -d are the same estimate, so the ring mean of N offsets has variance 2 sum(var) / N^2
        var = c / ((k - 1) * n[ok])
        errors.append(float(np.sqrt(2.0 * var.sum()) / ok.sum()) if ok.any() else float("nan"))
    return values, errors
