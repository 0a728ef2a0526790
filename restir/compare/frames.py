"""A run's frames summarized as they arrive, in memory independent of their number.

For `compare` and `sweep`: the running sum, each frame's relMSE and the accumulated image's after
it, batch means of consecutive frames for the bias check (`_Blocks`), and, for the frames after
the warm-up, the error's structure (correlation factors at every block size, the temporal
correlation of consecutive frames; structure.py) and an evenly spaced subset for the denoiser
(denoise.FrameSubset).
"""
import numpy as np

from . import structure
from .denoise import FrameSubset
from .reference import Reference

MAX_BLOCKS = 64  # batch means kept per method: between 32 and 64 equal blocks of frames


class _Blocks:
    """Batch means of consecutive frames in at most MAX_BLOCKS equal blocks: when the blocks fill
    up, neighbours merge and the block length doubles, so any number of frames is summarized in
    bounded memory."""

    def __init__(self):
        self.sums, self.counts, self.length = [], [], 1

    def add(self, frame):
        if self.sums and self.counts[-1] < self.length:
            self.sums[-1] += frame
            self.counts[-1] += 1
        else:
            self.sums.append(frame.astype(np.float64))
            self.counts.append(1)
        if len(self.sums) > MAX_BLOCKS:
            pairs = range(0, len(self.sums) - 1, 2)
            merged = [(self.sums[i] + self.sums[i + 1], self.counts[i] + self.counts[i + 1]) for i in pairs]
            if len(self.sums) % 2:
                merged.append((self.sums[-1], self.counts[-1]))
            self.sums, self.counts = [m[0] for m in merged], [m[1] for m in merged]
            self.length *= 2

    def full(self) -> np.ndarray:
        """(B, H, W, 3) means of the complete blocks."""
        keep = [s / c for s, c in zip(self.sums, self.counts) if c == self.length]
        return np.stack(keep) if keep else np.zeros((0,))


class FrameStats:
    """Frames of one run, summarized as they arrive (see the module's docstring). Frames with an
    index below `warmup` count for the accumulated image and the bias check only. If no frame
    is past the warm-up, the last frame stands in for the per-frame measures (as for relMSE)."""

    def __init__(self, reference: Reference, warmup: int = 0):
        self.ref = reference.image
        self.warmup = warmup
        self.total = np.zeros(self.ref.shape)
        self.blocks = _Blocks()
        self.frame_err, self.acc_err = [], []
        self.factors = {b: [] for b in structure.BLOCK_SIZES}
        self.temporal = []
        self.subset = FrameSubset()
        self.count = 0
        self.last = None
        self._last_error = None

    def add(self, frame):
        x = np.array(frame, np.float64)  # a copy: integrators reuse their output buffer
        e = structure.relative_error(x, self.ref)
        if self.count >= self.warmup:
            for b in self.factors:
                self.factors[b].append(structure.correlation_factor(e, b))
            if self.count > self.warmup:  # both frames of the pair measured
                self.temporal.append(structure.temporal_correlation(self._last_error, e))
            self.subset.offer(self.count, frame)
        self.count += 1
        self.total += x
        self.blocks.add(x)
        self.frame_err.append(float(np.mean(e * e)))  # relMSE (metrics.relmse) of the frame
        self.acc_err.append(float(np.mean(structure.relative_error(self.total / self.count, self.ref) ** 2)))
        self.last, self._last_error = x, e
        return self

    def structure(self) -> dict:
        """The correlation factor per block size (mean over measured frames) and the temporal
        correlation (mean over consecutive measured pairs; None with fewer than two)."""
        factors = self.factors
        if self.count and not factors[structure.BLOCK_SIZES[0]]:
            factors = {b: [structure.correlation_factor(self._last_error, b)] for b in factors}
        return {"correlation_factor": {str(b): _mean(v) for b, v in factors.items()},
                "temporal_correlation": _mean(self.temporal) if self.temporal else None}

    def denoise_frames(self) -> tuple:
        """(indices, frames) for the denoiser: the measured subset, or the last frame if none."""
        if self.subset.frames:
            return list(self.subset.indices), list(self.subset.frames)
        return [self.count - 1], [self.last.astype(np.float32)]


def _mean(values):
    v = np.asarray(values, np.float64)
    v = v[np.isfinite(v)]
    return float(v.mean()) if len(v) else None
