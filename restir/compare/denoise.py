"""Frames through Open Image Denoise, as a real-time user of ReSTIR sees them.

OIDN's RT filter in HDR mode with albedo and normal guides (restir/aov.py: noise-free, averaged
over AOV_SAMPLES camera samples, so `clean_aux`). The denoiser's time is not a method's: every
method is denoised the same way at the same size, after its frames are timed.

Where OIDN runs: on the GPU when the methods render there and PyTorch can reach it (pyoidn
reaches OIDN's CUDA device only through PyTorch's CUDA tensors), else on the host CPU. A GPU
denoise that fails falls back to the host for every frame after it, so that all frames of a
comparison are denoised alike, and `where` says so.

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
    device: str = "cpu"  # where OIDN runs: "cpu" (the host) or "cuda"
    fallback: str | None = None  # why a GPU denoiser went to the host

    @property
    def where(self) -> str:
        place = "the GPU (CUDA)" if self.device == "cuda" else "the host CPU"
        return place + (f"; the GPU was tried and failed: {self.fallback}" if self.fallback else "")

    @classmethod
    def for_scene(cls, scene, base) -> "Denoiser":
        """The guides of `scene` at `base`'s size (the first hit's albedo and normal)."""
        from ..aov import AOV_SAMPLES, compute_aovs
        from ..api import make_integrator, sized_scene

        require_oidn()
        cfg = dataclasses.replace(base, method="pt", settings={}, spp=1, frames=1)
        aux = compute_aovs(make_integrator(sized_scene(scene, cfg), cfg), ("albedo", "normal"), AOV_SAMPLES)
        return cls.from_guides(aux, base.device)

    @classmethod
    def from_guides(cls, aux: dict, device: str) -> "Denoiser":
        """From the albedo and normal layers (restir/aov.py), OIDN on the GPU where the renderer's
        device is CUDA and PyTorch reaches it."""
        return cls(np.clip(aux["albedo"], 0.0, 1.0).astype(np.float32), aux["normal"].astype(np.float32),
                   device="cuda" if str(device).startswith("cuda") and _torch_cuda() else "cpu")

    def __call__(self, frame) -> np.ndarray:
        import pyoidn

        color = np.clip(np.nan_to_num(np.asarray(frame, np.float32)), 0.0, None)
        if self.device == "cuda":
            try:
                return self._on_gpu(color)
            except Exception as e:  # noqa: BLE001  (any failure of the optional GPU path)
                self.device, self.fallback = "cpu", f"{type(e).__name__}: {e}"
        return np.asarray(pyoidn.denoise(color, self.albedo, self.normal, hdr=True, clean_aux=True), np.float32)

    def _on_gpu(self, color: np.ndarray) -> np.ndarray:
        import pyoidn
        import torch

        def gpu(x):
            return torch.from_numpy(np.ascontiguousarray(x, np.float32)).cuda()

        out = pyoidn.denoise(gpu(color), gpu(self.albedo), gpu(self.normal), hdr=True, clean_aux=True)
        return out.cpu().numpy().astype(np.float32)


def _torch_cuda() -> bool:
    """PyTorch with a CUDA device (what pyoidn needs to denoise on the GPU)."""
    try:
        import torch

        return bool(torch.cuda.is_available())
    except Exception:  # noqa: BLE001  (not installed, or a broken install: the host denoises)
        return False
