"""Frames through Open Image Denoise, as a real-time user of ReSTIR sees them.

OIDN's RT filter in HDR mode with albedo and normal guides (restir/aov.py: noise-free, averaged
over AOV_SAMPLES camera samples, so `clean_aux`). The denoiser's time is not a method's: every
method is denoised the same way at the same size, after its frames are timed.

Which frames: every frame after the warm-up when there are at most 2 * TARGET of them, else an
evenly spaced subset of between TARGET + 1 and 2 * TARGET (`FrameSubset`), so that a long
equal-time run is not denoised a thousand times.
"""
import dataclasses

import numpy as np

from ..config import ConfigError

TARGET = 8  # at least this many measured frames are denoised (all of them when there are fewer)


def require_oidn() -> None:
    try:
        import pyoidn  # noqa: F401
    except ImportError:
        raise ConfigError("--denoise needs Open Image Denoise: pip install 'restir[denoise]'") from None


class FrameSubset:
    """Keeps every `stride`-th of the frames it is offered (stride 1, 2, 4, ...): when more than
    2 * TARGET are kept, every other one is dropped and the stride doubles. Memory stays bounded
    and the kept frames stay evenly spaced, the first measured frame among them."""

    def __init__(self, target: int = TARGET):
        self.target, self.stride, self.offered = target, 1, 0
        self.frames, self.indices = [], []

    def offer(self, index: int, frame) -> None:
        if self.offered % self.stride == 0:
            self.frames.append(np.array(frame, np.float32))  # a copy: integrators reuse their output buffer
            self.indices.append(index)
            if len(self.frames) > 2 * self.target:
                self.frames, self.indices = self.frames[::2], self.indices[::2]
                self.stride *= 2
        self.offered += 1


@dataclasses.dataclass
class Denoiser:
    """OIDN with one scene's guides; `denoiser(frame)` is the denoised frame (H, W, 3)."""
    albedo: np.ndarray
    normal: np.ndarray

    @classmethod
    def for_scene(cls, scene, base) -> "Denoiser":
        """The guides of `scene` at `base`'s size (the first hit's albedo and normal)."""
        from ..aov import AOV_SAMPLES, compute_aovs
        from ..api import make_integrator, sized_scene

        require_oidn()
        cfg = dataclasses.replace(base, method="pt", settings={}, spp=1, frames=1)
        aux = compute_aovs(make_integrator(sized_scene(scene, cfg), cfg), ("albedo", "normal"), AOV_SAMPLES)
        return cls(np.clip(aux["albedo"], 0.0, 1.0).astype(np.float32), aux["normal"].astype(np.float32))

    def __call__(self, frame) -> np.ndarray:
        import pyoidn

        color = np.clip(np.nan_to_num(np.asarray(frame, np.float32)), 0.0, None)
        return np.asarray(pyoidn.denoise(color, self.albedo, self.normal, hdr=True, clean_aux=True), np.float32)
