"""Python API: load a scene, render it with a method, get numpy images and stats back.

    import restir
    scene = restir.load_scene("scene.xml", spp=64, res=256)   # as mi.load_file(path, **params)
    scene = restir.load_scene("builtin:cornell-box", width=128)
    result = restir.render(scene, method="restir-di", spp=1, frames=16)   # RenderConfig fields
    result.image        # (H, W, 3) float32, linear RGB, mean over frames
    result.stats        # per-stage ms, rays/s, bytes per pixel, ...
    restir.write_image("out.exr", result)                     # .exr, .png, .jpg, .npy
"""
import contextlib
import copy
import dataclasses
import inspect
import io
import os
import signal
import sys
import tempfile
import threading
import time
from dataclasses import dataclass

import numpy as np

from .config import ConfigError, RenderConfig
from .film import PixelMoments
from .scene.builtin import BUILTINS, builtin_scene
from .scene.errors import SceneError
from .scene.scene import Scene, build_scene
from .scene.upload import DeviceScene
from .scene.xml_loader import load_xml


def _define_value(v) -> str:
    """A parameter value as Mitsuba's XML substitution takes it (numbers or strings)."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float, str, np.integer, np.floating)):
        return str(v)
    raise SceneError(f"parameter value {v!r} is not a number or a string")


def load_scene(spec, defines: dict | None = None, *, missing_textures: str = "error", progress=None,
               **params) -> Scene:
    """Load a scene, the way Mitsuba 3's loaders are called.

    - a Mitsuba 3 XML file: keyword parameters set its `<default name=...>` values, as
      `mi.load_file(path, **params)` does (`load_scene("scene.xml", spp=64, res=256)`); numbers or
      strings. A parameter the scene never uses is an error (a misspelling would otherwise be
      ignored). `defines` is the same as a dict (the CLI's -D: there an unused name only warns).
    - `builtin:NAME`: keyword arguments go to the builtin (`width=`, `height=`, `spp=`, ...;
      `restir render --help` lists the builtins).
    - a pbrt-v4 file (`.pbrt`; docs/guide/pbrt.md says what is read, refused and approximated).
    - a glTF 2.0 file (`.gltf`, `.glb`; docs/guide/gltf.md); `camera="NAME"` picks a camera node,
      `fps=` the frames per second its animations play at (30 by default).
    - a dict: a scene in `mi.load_dict`'s form ({"type": "scene", "sensor": {...}, ...}).

    `missing_textures="grey"` renders a bitmap whose file is missing as constant grey (0.5), with
    a warning, instead of stopping (downloaded scenes often lack a texture).

    `progress(done, total)`, when given, is called as the scene's top-level elements are built
    (a large scene spends its load reading meshes there); `restir render` shows it as a bar.
    """
    if isinstance(spec, dict):
        if defines or params:
            raise SceneError("parameters apply to XML files and builtins; put the values in the dict")
        return build_scene(copy.deepcopy(spec), str(spec.get("id", "dict-scene")), missing_textures, progress)
    if not isinstance(spec, (str, os.PathLike)):
        raise SceneError(f"a scene is an XML path, 'builtin:NAME' or a dict, not {type(spec).__name__}")
    spec = os.fspath(spec)
    if spec.startswith("builtin:"):
        name = spec.split(":", 1)[1]
        if defines:
            raise SceneError("-D defines apply to XML scenes only", spec)
        if name in BUILTINS:
            accepted = inspect.signature(BUILTINS[name]).parameters
            if not any(p.kind == p.VAR_KEYWORD for p in accepted.values()):
                unknown = sorted(set(params) - set(accepted))
                if unknown:
                    raise SceneError(f"unknown parameter(s) {', '.join(unknown)} (builtin:{name} takes "
                                     f"{', '.join(accepted)})", spec)
        return build_scene(builtin_scene(name, **params), name, missing_textures, progress)
    if spec.lower().endswith((".gltf", ".glb")):
        options = {**(defines or {}), **params}
        unknown = sorted(set(options) - {"camera", "fps"})
        if unknown:
            raise SceneError(f"unknown parameter(s) {', '.join(unknown)} for a glTF file (it takes camera=NAME and "
                             "fps=FRAMES_PER_SECOND)", spec)
        from .scene.gltf.reader import DEFAULT_FPS, load_gltf

        try:
            fps = float(options.get("fps", DEFAULT_FPS))
        except (TypeError, ValueError):
            raise SceneError(f"fps must be a number, not {options.get('fps')!r}", spec) from None
        return build_scene(load_gltf(spec, options.get("camera"), fps), spec, missing_textures, progress)
    if spec.lower().endswith(".pbrt"):
        if defines or params:
            raise SceneError("parameters (-D, keywords) apply to Mitsuba XML files and builtins, not to pbrt-v4 files",
                             spec)
        from .scene.pbrt.reader import load_pbrt

        return build_scene(load_pbrt(spec), spec, missing_textures, progress)
    merged = {k: _define_value(v) for k, v in {**(defines or {}), **params}.items()}
    return build_scene(load_xml(spec, merged, required=set(params)), spec, missing_textures, progress)


@dataclass
class RenderResult:
    image: np.ndarray       # (H, W, 3) mean of all samples
    sample_var: np.ndarray  # (H, W, 3) population variance of the samples (float64)
    samples: int            # samples per pixel in total (spp * frames)
    stats: dict
    frame_sums: np.ndarray | None = None  # (4, H, W, 3): sums of frame means^1..^4 (float64)
    frame_images: np.ndarray | None = None  # (F, H, W, 3) when RenderConfig.keep_frames
    aovs: dict | None = None  # {name: (H, W, 3)} for RenderConfig.aovs (restir/aov.py)

    def __repr__(self) -> str:
        st = self.stats
        mean = ", ".join(f"{v:.4g}" for v in self.image.reshape(-1, 3).mean(axis=0))
        return (f"RenderResult({st.get('method')} on {st.get('scene')}: {st.get('width')}x{st.get('height')}, "
                f"{st.get('spp_per_frame')} spp x {st.get('frames')} frames, {st.get('total_ms', 0.0):.0f} ms, "
                f"mean RGB ({mean}))")

    def _repr_png_(self) -> bytes:
        """Inline preview in notebooks: the image tonemapped to sRGB (exposure 0)."""
        from PIL import Image

        from .image_io import linear_to_srgb

        x = np.nan_to_num(np.clip(self.image, 0.0, 1.0))
        buf = io.BytesIO()
        Image.fromarray((linear_to_srgb(x) * 255.0 + 0.5).astype(np.uint8)).save(buf, format="PNG")
        return buf.getvalue()

    @property
    def batches(self) -> np.ndarray | None:
        """Independent batch estimates of the image (the frames), when kept; frames are
        independent only for methods without temporal reuse."""
        return self.frame_images

    @property
    def frames(self) -> int:
        return self.stats["frames"]

    @property
    def batch_variance_of_mean(self) -> np.ndarray:
        """Variance of `image` estimated from the spread of the frame means (frames >= 2).

        Robust where single samples are heavy-tailed: each frame mean averages spp samples.
        """
        f = self.frames
        if f < 2:
            raise ValueError("batch statistics need at least 2 frames")
        s1, s2 = self.frame_sums[0], self.frame_sums[1]
        return np.maximum(s2 - s1 * s1 / f, 0.0) / (f - 1) / f

    @property
    def batch_skewness(self) -> np.ndarray:
        """Per-pixel skewness of the frame means (heavy tails make z-tests unreliable)."""
        s1, s2, s3, _ = (x / self.frames for x in self.frame_sums)
        var = np.maximum(s2 - s1 * s1, 0.0)
        m3 = s3 - 3 * s1 * s2 + 2 * s1 ** 3
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(var > 0, m3 / var ** 1.5, 0.0)

    @property
    def batch_excess_kurtosis(self) -> np.ndarray:
        """Per-pixel excess kurtosis of the frame means (0 for normal batch means)."""
        s1, s2, s3, s4 = (x / self.frames for x in self.frame_sums)
        var = np.maximum(s2 - s1 * s1, 0.0)
        m4 = s4 - 4 * s1 * s3 + 6 * s1 * s1 * s2 - 3 * s1 ** 4
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(var > 0, m4 / var ** 2 - 3.0, 0.0)

    @property
    def variance_of_mean(self) -> np.ndarray:
        """Unbiased estimate of the variance of `image` (samples of one pixel are independent for PT)."""
        n = self.samples
        return self.sample_var / max(n - 1, 1)


# Printed by Warp's native library (cuda_util.cpp, straight to file descriptor 2) on every
# wp.init() of a machine without the CUDA driver; no Warp setting silences it.
_CUDA_DRIVER_WARNING = "Could not find or load the NVIDIA CUDA driver"


class RenderInterrupted(KeyboardInterrupt):
    """Ctrl-C stopped a render (the frame in flight at its next launch, dropped). `result` holds
    the average of the frames that finished (stats["interrupted"] is True), or None when none had."""

    def __init__(self, result):
        super().__init__("render interrupted")
        self.result = result


@contextlib.contextmanager
def _sigint_between_frames(requested: list):
    """While rendering, Ctrl-C asks the frame loop to stop after the frame in flight instead of
    raising inside a launch: Warp's CPU kernels run on worker threads that a KeyboardInterrupt
    cannot stop, and unwinding past them crashed the interpreter at exit. A second Ctrl-C
    raises at once. (Only the main thread can own the handler; elsewhere nothing changes.)"""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def handler(signum, frame):
        if requested:
            raise KeyboardInterrupt
        requested.append(True)

    previous = signal.signal(signal.SIGINT, handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


def _init_warp(device: str = "cpu"):
    """wp.init(), without Warp's CUDA-driver warning when no CUDA device was asked for and Warp's
    own output is off (RESTIR_WARP_VERBOSE, restir/__init__.py); every other line it prints,
    errors included, still reaches stderr."""
    import warp as wp

    context = getattr(getattr(wp, "_src", None), "context", None) or getattr(wp, "context", None)
    initialized = getattr(context, "runtime", None) is not None  # then wp.init() prints nothing
    if initialized or device.startswith("cuda") or wp.config.log_level < wp.LOG_ERROR:
        wp.init()
        return wp
    with _stderr_without(_CUDA_DRIVER_WARNING):
        wp.init()
    return wp


@contextlib.contextmanager
def _stderr_without(marker: str):
    """Capture file descriptor 2 (native code writes there, not to sys.stderr) and pass on
    every line but those containing `marker`."""
    try:
        sys.stderr.flush()
        saved = os.dup(2)
    except (OSError, ValueError):  # no file descriptor 2: nothing to filter
        yield
        return
    with tempfile.TemporaryFile() as tmp:
        os.dup2(tmp.fileno(), 2)
        try:
            yield
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            tmp.seek(0)
            kept = [line for line in tmp.read().splitlines(keepends=True) if marker.encode() not in line]
            if kept:
                os.write(2, b"".join(kept))


def method_settings(scene: Scene, config: RenderConfig):
    """(the method's class, its checked settings, notes) for `config` on `scene`: every refusal of
    a setting (a ConfigError) before anything is built."""
    from .integrators import METHODS

    if config.method not in METHODS:
        raise ConfigError(f"unknown method '{config.method}' (available: {', '.join(METHODS)})")
    cls = METHODS[config.method]
    settings = cls.Settings.from_overrides(config.settings)
    fixed = cls.FIXED_MAX_DEPTH
    if fixed is not None and config.max_depth not in (None, fixed):
        raise ConfigError(f"method '{config.method}' computes max_depth {fixed} (direct illumination) only")
    max_depth = fixed or (config.max_depth if config.max_depth is not None else scene.max_depth)
    notes = []
    if fixed is not None and config.max_depth is None and scene.max_depth != fixed:
        notes.append(f"method '{config.method}' renders max_depth {fixed} (the only depth it computes), "
                     f"not the scene's max_depth {scene.max_depth}")
    settings = dataclasses.replace(settings, seed=config.seed, spp=config.spp or scene.spp, max_depth=max_depth,
                                   camera_motion=config.camera_motion, camera_speed=config.camera_speed,
                                   rr_depth=scene.rr_depth, hide_emitters=scene.hide_emitters)
    settings.check_common()
    cls.check_settings(settings)
    problem = cls.motion_refusal(settings) if scene.animation is not None else None
    if problem:
        raise ConfigError(f"the scene is animated, and {problem} (docs/guide/animation.md)")
    return cls, settings, notes


def make_integrator(scene: Scene, config: RenderConfig, on_compile=None, dscene=None):
    """The method's integrator for `scene` (uploaded here, or `dscene`: the scene already on the
    device, as the viewer keeps it across integrators)."""
    cls, settings, notes = method_settings(scene, config)
    if dscene is None:
        try:
            dscene = DeviceScene(scene, config.device, config.tracer, config.jitter)
        except RuntimeError as e:
            raise ConfigError(str(e)) from None
    try:
        integ = cls(dscene, settings, config.device, config.slices, on_compile=on_compile)
    except (MemoryError, RuntimeError) as e:
        if isinstance(e, RuntimeError) and "allocate" not in str(e).lower():
            raise
        cam = scene.camera
        raise ConfigError(f"not enough memory on {config.device} for the buffers of {config.method} at "
                          f"{cam.width}x{cam.height}: a smaller film, or another device") from None
    integ.reverse_launch = config.debug_reverse_launch
    integ.notes.extend(notes)
    return integ


def sized_scene(scene: Scene, config: RenderConfig) -> Scene:
    """`scene` with the film size config.width / config.height where they are given (a copy;
    the scene itself is left as it is)."""
    from . import limits

    if config.width or config.height:
        scene = copy.copy(scene)
        scene.camera = copy.copy(scene.camera)
        scene.camera.width = config.width or scene.camera.width
        scene.camera.height = config.height or scene.camera.height
    problem = limits.film_problem(scene.camera.width, scene.camera.height)
    if problem:  # the scene's size with one side given (the other is the scene's)
        raise ConfigError(problem)
    return scene


def check_device(config: RenderConfig):
    """Initialize Warp for config.device and refuse a device this machine lacks; returns warp."""
    wp = _init_warp(config.device)
    if config.device.startswith("cuda") and wp.get_cuda_device_count() == 0:
        raise ConfigError(f"device '{config.device}' is not available: no CUDA device on this machine")
    try:
        wp.get_device(config.device)
    except Exception:
        raise ConfigError(f"device '{config.device}' is not available") from None
    return wp


def render(scene: Scene, config: RenderConfig | None = None, progress=None, on_compile=None,
           **settings) -> RenderResult:
    """Render `config.frames` frames and return their average with stats.

    The common settings may be given as keywords instead of a RenderConfig, or on top of one:
    `render(scene, method="restir-di", spp=1, frames=16, seed=3, settings={"candidates": 8})`
    (the fields of RenderConfig; an unknown keyword is an error). `progress`, if given, is called
    as progress(frames_done, frames_total) after each frame, and with fractional frames_done as
    a frame's samples finish. `on_compile`, if given, is called (no arguments) when loading the
    kernels takes long: they are being compiled, which happens once per configuration.
    """
    config = config or RenderConfig()
    if settings:
        fields = {f.name for f in dataclasses.fields(RenderConfig)}
        unknown = sorted(set(settings) - fields)
        if unknown:
            raise ConfigError(f"unknown render setting(s) {', '.join(unknown)} (known: {', '.join(sorted(fields))}; "
                              "method settings go in settings={...})")
        config = dataclasses.replace(config, **settings)
    config.validate()
    check_device(config)
    scene = sized_scene(scene, config)
    stop: list = []
    with _sigint_between_frames(stop):
        t_setup = time.perf_counter()
        integ = make_integrator(scene, config, on_compile)
        setup_ms = (time.perf_counter() - t_setup) * 1e3
        h, w = integ.height, integ.width
        moments = PixelMoments((h, w, 3))
        frame_sums = np.zeros((4, h, w, 3))
        frames = [] if config.keep_frames else None
        spp = integ.settings.spp
        t0 = time.perf_counter()
        done = 0
        if progress:
            integ.on_samples = lambda n, spp: progress(done + n / spp, config.frames)
        from .integrators.base import FrameInterrupted

        integ.stop_requested = lambda: bool(stop)
        for f in range(config.frames):
            if stop:
                break
            try:
                mean, var = integ.render_frame(f)
            except FrameInterrupted:
                break
            moments.add(mean, var, spp)
            m = mean.astype(np.float64)
            frame_sums += (m, m ** 2, m ** 3, m ** 4)
            if frames is not None:
                frames.append(mean.astype(np.float32))
            done += 1
            if progress:
                progress(f + 1, config.frames)
    stopped = bool(stop) and done < config.frames  # a Ctrl-C after the last frame's last launch stops nothing
    if stopped and done == 0:
        raise RenderInterrupted(None)
    total_ms = (time.perf_counter() - t0) * 1e3
    stats = {"scene": scene.name, "method": config.method, "width": w, "height": h, "spp_per_frame": spp,
             "frames": done, **integ.stats(), "total_ms": total_ms, "setup_ms": setup_ms,
             "triangles": scene.num_triangles, "interrupted": stopped}
    stats["ms_per_frame"] = stats["stage_total_ms"] / done
    aovs = None
    if config.aovs:
        from .aov import compute_aovs

        aovs = compute_aovs(integ, config.aovs, done)
    result = RenderResult(moments.mean.astype(np.float32), moments.variance, moments.n, stats, frame_sums,
                          np.stack(frames) if frames is not None else None, aovs)
    if stopped:
        raise RenderInterrupted(result)
    return result


def write_image(path: str, image, exposure: float = 0.0) -> None:
    """Write an image (an (H, W, 3) array or a RenderResult) in the format of the path's
    extension: .exr (linear float), .png / .jpg (tonemapped sRGB, `exposure` in stops), .npy."""
    from .image_io import write_image as _write

    _write(os.fspath(path), np.asarray(getattr(image, "image", image), dtype=np.float32), exposure)

