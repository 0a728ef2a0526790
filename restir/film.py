"""Per-pixel moments of a render: one implementation for every method and for the API.

Batches (a frame's samples, or a single sample) are combined in float64 by Chan et al.'s
parallel update, so a mean and a variance never come from a second moment minus a squared mean
(which cancels catastrophically in float32). Device kernels that average several samples per
pixel in one launch use Welford's update (`welford_add`), the one-sample case of the same rule.
"""
import numpy as np
import warp as wp


class PixelMoments:
    """Mean and population variance per pixel over all samples added so far."""

    def __init__(self, shape):
        self.n = 0
        self.mean = np.zeros(shape)
        self.m2 = np.zeros(shape)

    def add(self, mean, var=None, count: int = 1) -> None:
        """Add a batch of `count` samples with per-pixel `mean` and population variance `var`;
        var=None adds one sample (Welford's update, the count-1 case of the same rule)."""
        mean = np.asarray(mean, dtype=np.float64)
        delta = mean - self.mean
        total = self.n + count
        if var is None:
            if count != 1:
                raise ValueError("a batch of several samples needs its variance")
            self.mean += delta / total
            self.m2 += delta * (mean - self.mean)
        else:
            self.mean += delta * (count / total)
            self.m2 += np.asarray(var, dtype=np.float64) * count + delta ** 2 * (self.n * count / total)
        self.n = total

    @property
    def variance(self) -> np.ndarray:
        return self.m2 / max(self.n, 1)


@wp.struct
class Welford:
    mean: wp.vec3
    m2: wp.vec3
    n: int


@wp.func
def welford_add(w: Welford, x: wp.vec3) -> Welford:
    out = w
    out.n = w.n + 1
    delta = x - w.mean
    out.mean = w.mean + delta / float(out.n)
    out.m2 = w.m2 + wp.cw_mul(delta, x - out.mean)
    return out
