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


@wp.kernel
def film_add_kernel(L: wp.array(dtype=wp.vec3), n: int, mean: wp.array(dtype=wp.vec3d), m2: wp.array(dtype=wp.vec3d)):
    """Welford's update in float64 with the (n + 1)-th sample, the same operations as
    PixelMoments.add(L) (n = 0 starts the pixel: its mean is the sample, its m2 zero)."""
    i = wp.tid()
    x = wp.vec3d(wp.float64(L[i][0]), wp.float64(L[i][1]), wp.float64(L[i][2]))
    m = wp.vec3d()
    s = wp.vec3d()
    if n > 0:
        m = mean[i]
        s = m2[i]
    delta = x - m
    total = wp.float64(n + 1)
    m_new = m + delta / total
    mean[i] = m_new
    m2[i] = s + wp.cw_mul(delta, x - m_new)


class SampleFilm:
    """A frame's per-pixel moments over its samples, kept on the device: each sample's radiance
    (a device array) is added there, and the host reads the frame once. A one-sample frame is its
    sample: no buffers, nothing accumulated (the default of the ReSTIR methods)."""

    def __init__(self, integ, spp: int):
        self.integ = integ
        self.spp = spp
        self.n = 0
        self.last = None
        if spp > 1:
            self.mean = integ.buffer("film_mean", wp.vec3d)
            self.m2 = integ.buffer("film_m2", wp.vec3d)

    def begin(self) -> None:
        self.n = 0
        self.last = None

    def add(self, L) -> None:
        """Add one sample's radiance per pixel (wp.array of vec3, one per pixel)."""
        if self.spp > 1:
            wp.launch(film_add_kernel, dim=self.integ.num_pixels, inputs=[L, self.n, self.mean, self.m2],
                      device=self.integ.device)
        self.last = L
        self.n += 1

    def read(self, shape) -> tuple[np.ndarray, np.ndarray]:
        """(mean as float32, population variance), each reshaped to `shape` (H, W, 3)."""
        if self.n == 1:
            mean = self.last.numpy().reshape(shape).copy()
            return mean, np.zeros(shape)
        return (self.mean.numpy().view(np.float64).reshape(shape).astype(np.float32),
                self.m2.numpy().view(np.float64).reshape(shape) / max(self.n, 1))
