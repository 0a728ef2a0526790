"""Image error metrics against a reference, as the field reports them.

relMSE and MAPE are per channel and pixel, averaged; their 0.01 in the denominator keeps dark
pixels from dominating (the convention of the ReSTIR papers and of Mitsuba's and Falcor's
comparison scripts). FLIP is NVIDIA's perceptual difference (the `flip-evaluator` package) in its
HDR mode; None when that package is not installed.
"""
import numpy as np

EPSILON = 0.01


def relmse(image, reference) -> float:
    """Mean of (x - y)^2 / (y^2 + 0.01) over pixels and channels."""
    x = np.asarray(image, np.float64)
    y = np.asarray(reference, np.float64)
    return float(np.mean((x - y) ** 2 / (y * y + EPSILON)))


def mape(image, reference) -> float:
    """Mean of |x - y| / (|y| + 0.01) over pixels and channels."""
    x = np.asarray(image, np.float64)
    y = np.asarray(reference, np.float64)
    return float(np.mean(np.abs(x - y) / (np.abs(y) + EPSILON)))


def flip(image, reference) -> float | None:
    """Mean HDR-FLIP error (0: identical), or None without the flip-evaluator package."""
    try:
        import flip_evaluator
    except ImportError:
        return None
    x = np.nan_to_num(np.clip(np.asarray(image, np.float32), 0.0, None))
    y = np.nan_to_num(np.clip(np.asarray(reference, np.float32), 0.0, None))
    _, mean_error, _ = flip_evaluator.evaluate(y, x, "HDR", applyMagma=False)
    return float(mean_error)


def relative_error_map(image, reference) -> np.ndarray:
    """Per-pixel relative error |x - y| / (|y| + 0.01), averaged over channels: the false-colour
    view of the report."""
    x = np.asarray(image, np.float64)
    y = np.asarray(reference, np.float64)
    return (np.abs(x - y) / (np.abs(y) + EPSILON)).mean(axis=-1)


def mean_bias(blocks, reference, reference_blocks=None):
    """The image-mean ratio to the reference and its z, from the validation harness.

    blocks: (B, H, W, 3) means of B consecutive, equally long blocks of frames (batch means:
    with temporal reuse consecutive frames are correlated, and blocks much longer than the
    history's memory are close to independent). reference_blocks: independent estimates of the
    reference (its frames, when rendered here) or None for an exact reference (a converged
    EXR). The test is on the channel average, one scalar image, so that correlated channels are
    not counted three times. Returns (ratio, z, mdb); z and mdb are None with fewer than 2 blocks.
    """
    from ..validation.stats import ZTestReport

    blocks = np.asarray(blocks, np.float64).mean(axis=-1)
    ref = np.asarray(reference, np.float64).mean(axis=-1)
    mean = blocks.mean(axis=0)
    ratio = float(mean.mean() / ref.mean()) if ref.mean() != 0 else float("nan")
    if len(blocks) < 2:
        return ratio, None, None
    var = blocks.var(axis=0, ddof=1) / len(blocks)
    ref_var, ref_batches = 0.0, None
    if reference_blocks is not None and len(reference_blocks) >= 2:
        ref_batches = np.asarray(reference_blocks, np.float64).mean(axis=-1)
        ref_var = ref_batches.var(axis=0, ddof=1) / len(ref_batches)
    rep = ZTestReport(mean, var, ref, ref_var, batches=blocks, ref_batches=ref_batches, df=len(blocks) - 1)
    return ratio, float(rep.image_z), float(rep.mdb)
