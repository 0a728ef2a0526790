"""The reference of a comparison: a given EXR, or the path tracer at N spp, cached on disk.

The cache key is a hash of the scene's content (every triangle, material, texture, the camera
and the environment, as loaded: an edited XML or mesh gives a new key), the render settings and
the package version, so that a stale reference is never reused. Cache folder: $RESTIR_CACHE or
~/.cache/restir, subfolder references/.
"""
import dataclasses
import hashlib
import json
import os

import numpy as np

from .. import __version__
from ..config import ConfigError, RenderConfig

REFERENCE_FRAMES = 16  # the path tracer's reference in this many independent frames (its variance)


@dataclasses.dataclass
class Reference:
    image: np.ndarray                 # (H, W, 3) float64
    source: str                       # "file PATH" or "pt N spp (cached KEY)"
    blocks: np.ndarray | None = None  # (B, H, W, 3) independent estimates (path tracer's frames), None: exact

    def own_relmse(self) -> float | None:
        """The relMSE the reference itself is expected to have (the variance of its mean from its
        independent blocks, over ref^2 + 0.01), or None for an exact one. Every error measured
        against it includes this much: E[(x - ref)^2] = E[(x - mu)^2] + E[(ref - mu)^2]."""
        if self.blocks is None or len(self.blocks) < 2:
            return None
        var = np.asarray(self.blocks, np.float64).var(axis=0, ddof=1) / len(self.blocks)
        return float(np.mean(var / (self.image ** 2 + 0.01)))


def scene_digest(scene) -> str:
    """sha256 of everything the scene's image depends on."""
    h = hashlib.sha256()
    for f in dataclasses.fields(scene):
        value = getattr(scene, f.name)
        h.update(f.name.encode())
        items = value if isinstance(value, list) else [value]
        for item in items:
            if isinstance(item, np.ndarray):
                h.update(str((item.dtype, item.shape)).encode())
                h.update(np.ascontiguousarray(item).tobytes())
            else:
                h.update(repr(item).encode())
    return h.hexdigest()


def cache_folder() -> str:
    root = os.environ.get("RESTIR_CACHE") or os.path.join(os.path.expanduser("~"), ".cache", "restir")
    return os.path.join(root, "references")


def load_reference_file(path: str, width: int, height: int) -> Reference:
    from ..image_io import ImageError, read_image

    if not os.path.isfile(path):
        raise ConfigError(f"--reference {path}: no such file")
    try:
        image = np.asarray(read_image(path), np.float64)
    except ImageError as e:  # unreadable, empty, or not RGB
        raise ConfigError(f"--reference {path}: {e}") from None
    if not np.isfinite(image).all():
        raise ConfigError(f"--reference {path}: {int((~np.isfinite(image)).any(-1).sum())} pixels are NaN or inf")
    if image.shape[:2] != (height, width):
        raise ConfigError(f"--reference {path}: {image.shape[1]}x{image.shape[0]} pixels, the comparison renders "
                          f"{width}x{height} (set --width/--height to the reference's size)")
    return Reference(image, f"file {path}")


def path_traced_reference(scene, spp: int, config: RenderConfig, progress=None) -> Reference:
    """The path tracer at `spp` samples per pixel in REFERENCE_FRAMES independent frames, loaded
    from the cache when present."""
    from ..api import render

    frames = REFERENCE_FRAMES if spp >= REFERENCE_FRAMES else max(2, spp)
    per_frame = max(1, spp // frames)
    cfg = RenderConfig(method="pt", spp=per_frame, frames=frames, width=config.width, height=config.height,
                       max_depth=config.max_depth, seed=0x5EF, device=config.device, keep_frames=True,
                       jitter=config.jitter)
    key = {"scene": scene_digest(scene), "spp": per_frame, "frames": frames, "width": config.width,
           "height": config.height, "max_depth": config.max_depth, "seed": cfg.seed, "version": __version__}
    if not config.jitter:  # only then: the keys of references rendered before the option stay valid
        key["jitter"] = False
    key_text = json.dumps(key, sort_keys=True)
    return _cached(key_text, lambda path: f"pt {per_frame * frames} spp ({frames} frames; cache {path})",
                   lambda: render(scene, cfg, progress=progress).frame_images)


def _cached(key_text: str, source, render_blocks) -> Reference:
    """The reference keyed by `key_text` from the cache, or `render_blocks()` ((B, H, W, 3)
    independent estimates) rendered now and stored; source(path) names it."""
    key = hashlib.sha256(key_text.encode()).hexdigest()[:24]
    path = os.path.join(cache_folder(), key + ".npz")
    if os.path.isfile(path):
        with np.load(path) as data:
            return Reference(data["image"], source(path), data["blocks"])
    blocks = np.asarray(render_blocks(), np.float32)
    image = blocks.astype(np.float64).mean(0)
    os.makedirs(os.path.dirname(path), exist_ok=True)
    tmp = path + f".{os.getpid()}.tmp.npz"
    np.savez_compressed(tmp, image=image, blocks=blocks, key=key_text)
    os.replace(tmp, path)  # atomic: a concurrent or interrupted run never leaves half a file
    return Reference(image, source(path), blocks)


MITSUBA_VARIANTS = ("llvm_ad_rgb", "scalar_rgb")


def mitsuba_reference(scene, scene_file: str, defines: dict | None, spp: int, config: RenderConfig) -> Reference:
    """Mitsuba 3 (the `reference` extra) renders the same XML file as the reference: 16 renders with
    independent seeds at spp / 16 each (their spread is the reference's variance), cached as the
    path tracer's are. The size and max_depth are passed as the XML's `resx`, `resy` and
    `max_depth` defaults, which the scene must declare when they differ from its own."""
    import re

    if not scene_file or scene_file.startswith("builtin:") or not os.path.isfile(scene_file):
        raise ConfigError("--reference mitsuba renders a Mitsuba 3 XML file; builtin scenes have none")
    try:
        import mitsuba as mi
    except ImportError:
        raise ConfigError("--reference mitsuba needs Mitsuba 3: pip install 'restir[reference]' (its llvm_ad_rgb "
                          "variant also needs Debian's libllvm19 and DRJIT_LIBLLVM_PATH; scalar_rgb works without)") from None
    text = open(scene_file).read()
    declared = set(re.findall(r'<default\s+name="([A-Za-z_][A-Za-z0-9_]*)"', text))
    params = {k: str(v) for k, v in (defines or {}).items()}
    wanted = {"resx": config.width, "resy": config.height, "max_depth": config.max_depth}
    own = {"resx": scene.camera.width, "resy": scene.camera.height, "max_depth": scene.max_depth}
    for k, v in wanted.items():
        if v is None or v == own[k]:
            continue
        if k not in declared:
            raise ConfigError(f"--reference mitsuba: {scene_file} declares no <default name=\"{k}\">, so Mitsuba "
                              f"cannot render it at {k} {v}; compare at the scene's own value ({own[k]})")
        params[k] = str(v)
    frames = REFERENCE_FRAMES if spp >= REFERENCE_FRAMES else max(2, spp)
    per_render = max(1, spp // frames)
    key_text = json.dumps({"renderer": "mitsuba", "scene": scene_digest(scene), "params": params, "spp": per_render,
                           "renders": frames, "version": __version__}, sort_keys=True)
    # llvm_ad_rgb only where Dr.Jit is pointed at a libLLVM it supports (DRJIT_LIBLLVM_PATH: another
    # libLLVM found on the system can abort the process inside the JIT); scalar_rgb otherwise.
    # RESTIR_MITSUBA_VARIANT overrides.
    variant = os.environ.get("RESTIR_MITSUBA_VARIANT") or \
        (MITSUBA_VARIANTS[0] if os.environ.get("DRJIT_LIBLLVM_PATH") else MITSUBA_VARIANTS[1])
    try:
        mi.set_variant(variant)
    except Exception as e:
        raise ConfigError(f"--reference mitsuba: Mitsuba's variant {variant} is not usable here ({e})") from None

    def render_blocks():
        ms = mi.load_file(scene_file, **params)
        return np.stack([np.asarray(mi.render(ms, spp=per_render, seed=7000 + i), np.float64)[..., :3]
                         for i in range(frames)])

    return _cached(key_text, lambda path: f"mitsuba {variant} {per_render * frames} spp (cache {path})", render_blocks)
