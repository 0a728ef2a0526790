"""`compare`: several methods on one scene with the same budget, measured against a reference.

Budgets. Equal time: each method renders frames until its wall time (frames only: kernel
compilation is done beforehand, on a throwaway 16x16 render of the same configuration) reaches
the budget; the frame that crosses it is kept. Equal samples: each method renders N samples per
pixel in total (N / spp frames). Otherwise every method renders `frames` frames.

Both conventions of the field are reported. Per frame: the mean relMSE of single frames after
`warmup` frames (what a real-time application shows). Accumulated: the average of every frame
rendered within the budget (what an offline user gets). The bias check (image-mean ratio and its
z, restir.validation's image-level test) uses batch means of consecutive frames (see
`_Blocks`), since temporal reuse correlates consecutive frames.
"""
import dataclasses
import time

import numpy as np

from ..config import ConfigError, RenderConfig, method_settings
from . import metrics
from .reference import Reference, load_reference_file, path_traced_reference

MAX_BLOCKS = 64  # batch means kept per method: between 32 and 64 equal blocks of frames


@dataclasses.dataclass
class MethodSpec:
    """One `--method` argument: NAME[:key=value,key=value...]. `spp` among the keys sets the
    samples per pixel per frame; every other key is a setting of the method (`restir info`)."""
    label: str
    method: str
    settings: dict
    spp: int | None = None

    @classmethod
    def parse(cls, text: str) -> "MethodSpec":
        from ..integrators import METHODS

        name, _, rest = text.partition(":")
        name = name.strip()
        if name not in METHODS:
            raise ConfigError(f"--method {text}: unknown method '{name}' (available: {', '.join(METHODS)})")
        settings, spp = {}, None
        for item in filter(None, (s.strip() for s in rest.split(","))):
            key, eq, value = item.partition("=")
            if not eq:
                raise ConfigError(f"--method {text}: '{item}' is not key=value")
            if key.strip() == "spp":
                try:
                    spp = int(value)
                except ValueError:
                    raise ConfigError(f"--method {text}: spp '{value}' is not an integer") from None
                if spp < 1:
                    raise ConfigError(f"--method {text}: spp must be >= 1")
            else:
                settings[key.strip()] = value.strip()
        try:
            method_settings(METHODS[name].SETTINGS, settings)  # unknown keys and bad values, before any work
        except ConfigError as e:
            raise ConfigError(f"--method {text}: {e}") from None
        return cls(text, name, settings, spp)


@dataclasses.dataclass
class MethodResult:
    label: str
    method: str
    settings: dict
    spp: int
    frames: int
    seconds: float                 # wall time of the frames (compilation excluded)
    image: np.ndarray              # (H, W, 3) the accumulated image
    frame_seconds: list            # cumulative wall time after each frame
    frame_relmse: list             # relMSE of each single frame
    accumulated_relmse: list       # relMSE of the average of frames 0..i, after each frame i
    metrics: dict                  # see `compare`
    stats: dict                    # the integrator's stats (per-stage ms, bytes per pixel, counters)
    last_frame: np.ndarray | None = None
    denoised: np.ndarray | None = None  # the last frame through Open Image Denoise (compare(denoise=True))
    interrupted: bool = False           # Ctrl-C stopped it before its budget was spent


@dataclasses.dataclass
class Comparison:
    scene: str
    width: int
    height: int
    budget: str
    warmup: int
    reference: Reference
    methods: list
    notes: list = dataclasses.field(default_factory=list)
    interrupted: bool = False  # Ctrl-C: the methods up to the interrupted one, the rest not run

    def to_dict(self) -> dict:
        """Everything but the images, as plain JSON data."""
        return {"scene": self.scene, "width": self.width, "height": self.height, "budget": self.budget,
                "warmup": self.warmup, "reference": self.reference.source, "notes": list(self.notes),
                "interrupted": self.interrupted,
                "methods": [{k: v for k, v in dataclasses.asdict(m).items() if k not in ("image", "last_frame", "denoised")}
                            for m in self.methods]}


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
    """A run's frames summarized as they arrive, in memory independent of their number: the running
    sum, each frame's relMSE and the accumulated image's after it, the batch means (`_Blocks`),
    the last frame."""

    def __init__(self, reference: Reference):
        self.ref = reference.image
        self.total = np.zeros(self.ref.shape)
        self.blocks = _Blocks()
        self.frame_err, self.acc_err = [], []
        self.count = 0
        self.last = None

    def add(self, frame):
        x = np.asarray(frame, np.float64)
        self.count += 1
        self.total += x
        self.blocks.add(x)
        self.frame_err.append(metrics.relmse(x, self.ref))
        self.acc_err.append(metrics.relmse(self.total / self.count, self.ref))
        self.last = x
        return self


def measure(label, config: RenderConfig, frames: FrameStats, frame_seconds, reference: Reference, warmup: int,
            stats: dict) -> MethodResult:
    """A MethodResult from a run's frames and their cumulative times, with the metrics of `compare`."""
    ref = reference.image
    n = frames.count
    image = frames.total / n
    after = frames.frame_err[warmup:] if n > warmup else frames.frame_err[-1:]
    ratio, z, mdb = metrics.mean_bias(frames.blocks.full(), ref, reference.blocks)
    seconds = frame_seconds[-1]
    m = {"relmse_frame": float(np.mean(after)), "relmse_accumulated": frames.acc_err[-1],
         "mape": metrics.mape(image, ref), "flip": metrics.flip(image, ref), "mean_ratio": ratio, "mean_z": z,
         "mean_mdb": mdb, "frames_after_warmup": len(after), "ms_per_frame": 1e3 * seconds / n}
    return MethodResult(label, config.method, dict(config.settings), config.spp, n, seconds, image.astype(np.float32),
                        list(frame_seconds), frames.frame_err, frames.acc_err, m, stats, frames.last.astype(np.float32))


def _compile_first(scene, config: RenderConfig):
    """Load (compile if needed) the method's kernels on a 16x16 render, so that no budget is spent
    compiling."""
    from ..fanout import warm_kernels

    warm_kernels([(scene, config)])


def _run_method(scene, spec: MethodSpec, base: RenderConfig, reference: Reference, budget, warmup, progress):
    from ..api import make_integrator, sized_scene

    kind, amount = budget
    config = dataclasses.replace(base, method=spec.method, settings=dict(spec.settings), spp=spec.spp or 1)
    frames_max = -(-amount // config.spp) if kind == "spp" else amount if kind == "frames" else base.frames
    _compile_first(scene, config)
    integ = make_integrator(sized_scene(scene, config), config)
    frames, frame_seconds = FrameStats(reference), []
    elapsed = 0.0
    interrupted = False
    try:
        while frames.count < frames_max and not (kind == "time" and elapsed >= amount):
            t = time.perf_counter()
            mean, _ = integ.render_frame(frames.count)
            elapsed += time.perf_counter() - t
            frames.add(mean)
            frame_seconds.append(elapsed)
            if progress:
                progress(spec.label, min(1.0, elapsed / amount) if kind == "time" else frames.count / frames_max)
    except KeyboardInterrupt:  # Ctrl-C: keep the frames that finished (none: nothing to keep)
        if frames.count == 0:
            raise
        interrupted = True
    result = measure(spec.label, config, frames, frame_seconds, reference, warmup, integ.stats())
    result.interrupted = interrupted
    return result


def _fan_out(scene, specs, base, reference, budget, warmup, workers, ray, progress):
    """The methods as independent renders (equal samples or frames), measured here."""
    from ..fanout import run_tasks

    kind, amount = budget
    configs = []
    for spec in specs:
        spp = spec.spp or 1
        frames = -(-amount // spp) if kind == "spp" else amount
        configs.append(dataclasses.replace(base, method=spec.method, settings=dict(spec.settings), spp=spp,
                                           frames=frames, keep_frames=True))
    renders = run_tasks([(scene, c) for c in configs], workers=workers, ray=ray,
                        progress=(lambda done, total: progress("methods", done / total)) if progress else None)
    out = []
    for spec, cfg, r in zip(specs, configs, renders):
        fs = FrameStats(reference)
        for x in r.frame_images:
            fs.add(x)
        ms = r.stats["ms_per_frame"]
        out.append(measure(spec.label, cfg, fs, [ms * 1e-3 * (i + 1) for i in range(fs.count)], reference, warmup,
                           r.stats))
    return out


def compare(scene, methods, *, reference: str | None = None, reference_spp: int = 1024,
            equal_time: float | None = None, equal_spp: int | None = None, frames: int = 16, warmup: int = 4,
            seed: int = 0, width: int | None = None, height: int | None = None, max_depth: int | None = None,
            device: str = "cpu", progress=None, workers: int | None = None, ray: str | None = None,
            denoise: bool = False, scene_file: str | None = None, defines: dict | None = None) -> Comparison:
    """Render every method in `methods` (MethodSpec or 'name:key=value,...' strings) on `scene`
    with the same budget and measure each against the reference.

    reference: an image file (EXR, PNG, NPY) of the same size, None for the path tracer at
    `reference_spp`, or "mitsuba" for Mitsuba 3 at `reference_spp` on `scene_file` (the XML the
    scene was loaded from, with its `defines`); both cached, see reference.py. Budget: `equal_time` seconds of frames per method,
    or `equal_spp` samples per pixel in total, or `frames` frames each (also the cap on frames under
    equal time, when given explicitly as more than the default). `progress(label, fraction)` is
    called after every frame (label "reference" while the reference renders).

    Each MethodResult.metrics holds relmse_frame (mean over frames after `warmup`),
    relmse_accumulated, mape, flip (None without flip-evaluator), mean_ratio with mean_z and
    mean_mdb (the image-level bias test; None with fewer than 2 blocks), ms_per_frame.

    workers (default: one per core for equal samples or frames, 1 at equal time) > 1 or ray: the
    methods render as independent tasks (restir/fanout.py), for equal samples or frames only: an
    equal-time comparison needs each method alone on the machine. (Their ms per frame are then
    measured under each other's load.)

    denoise: each method's last frame is also denoised by Intel Open Image Denoise (the `pyoidn`
    package, the `denoise` extra) with albedo and normal AOVs (restir/aov.py), the real-time use
    of ReSTIR; MethodResult.denoised holds it and metrics["relmse_denoised_frame"] its error.
    """
    from ..api import check_device, sized_scene

    specs = [m if isinstance(m, MethodSpec) else MethodSpec.parse(m) for m in methods]
    if not specs:
        raise ConfigError("compare needs at least one --method")
    if len({s.label for s in specs}) != len(specs):
        raise ConfigError("the same --method is given twice")
    if equal_time is not None and equal_spp is not None:
        raise ConfigError("give --equal-time or --equal-spp, not both")
    if equal_time is not None and not equal_time > 0:
        raise ConfigError("--equal-time must be > 0 seconds")
    if equal_spp is not None and equal_spp < 1:
        raise ConfigError("--equal-spp must be >= 1")
    if workers is None:
        from ..fanout import default_workers

        workers = 1 if equal_time is not None else min(default_workers(), len(specs))
    fan_out = ray is not None or workers > 1
    if fan_out and equal_time is not None:
        raise ConfigError("--equal-time renders the methods one after another (each alone on the machine, or "
                          "its time would include the others' load); --workers and --ray apply to equal samples "
                          "or frames")
    if denoise:
        try:
            import pyoidn  # noqa: F401
        except ImportError:
            raise ConfigError("--denoise needs Open Image Denoise: pip install 'restir[denoise]'") from None
    if frames < 1 or warmup < 0 or reference_spp < 1:
        raise ConfigError("frames and reference spp must be >= 1, warmup >= 0")
    from ..integrators import METHODS

    notes = []
    fixed = {getattr(METHODS[s.method], "FIXED_MAX_DEPTH", None) for s in specs} - {None}
    for depth in fixed:  # restir-di computes max_depth 2 only: everything is compared at that depth
        if max_depth is not None and max_depth != depth:
            raise ConfigError(f"max_depth {max_depth}: "
                              f"{', '.join(s.label for s in specs if getattr(METHODS[s.method], 'FIXED_MAX_DEPTH', None))} "
                              f"computes max_depth {depth} only")
        if max_depth is None:
            notes.append(f"every method and the reference at max_depth {depth}, the only depth of "
                         + ", ".join(s.label for s in specs if getattr(METHODS[s.method], "FIXED_MAX_DEPTH", None)))
        max_depth = depth
    base = RenderConfig(frames=10 ** 9 if equal_time is not None else frames, width=width, height=height,
                        max_depth=max_depth, seed=seed, device=device)
    base.validate()
    check_device(base)
    sized = sized_scene(scene, base)
    w, h = sized.camera.width, sized.camera.height
    base = dataclasses.replace(base, width=w, height=h)
    if reference == "mitsuba":
        from .reference import mitsuba_reference

        ref = mitsuba_reference(scene, scene_file, defines, reference_spp,
                                dataclasses.replace(base, width=width, height=height, max_depth=max_depth))
    elif reference is not None:
        ref = load_reference_file(reference, w, h)
    else:
        ref = path_traced_reference(scene, reference_spp, base,
                                    progress=(lambda done, total: progress("reference", done / total)) if progress else None)
    if equal_time is not None:
        budget, text = ("time", equal_time), f"equal time: {equal_time:g} s of frames per method"
    elif equal_spp is not None:
        budget, text = ("spp", equal_spp), f"equal samples: {equal_spp} spp per pixel per method"
    else:
        budget, text = ("frames", frames), f"{frames} frames per method"
    interrupted_run = False
    if fan_out:
        results = _fan_out(scene, specs, base, ref, budget, warmup, workers, ray, progress)
    else:
        results = []
        for s in specs:
            try:
                results.append(_run_method(scene, s, base, ref, budget, warmup, progress))
            except KeyboardInterrupt:
                if not results:
                    raise
                results.append(None)
            if results[-1] is None or results[-1].interrupted:
                break
        results = [r for r in results if r is not None]
        if len(results) < len(specs) or results[-1].interrupted:
            notes.append("interrupted (Ctrl-C): " + ", ".join(
                f"{r.label} {'stopped after ' + str(r.frames) + ' frames' if r.interrupted else 'complete'}"
                for r in results) + "; not run: " + (", ".join(s.label for s in specs[len(results):]) or "none"))
            interrupted_run = True
    if denoise:
        _denoise(scene, base, results, ref)
    return Comparison(scene.name, w, h, text, warmup, ref, results, notes,
                      interrupted=interrupted_run)


def _denoise(scene, base: RenderConfig, results, reference: Reference):
    """Each method's last frame through OIDN's RT filter (HDR, with noise-free albedo and normal
    averaged over 64 camera samples)."""
    import pyoidn

    from ..aov import AOV_SAMPLES, compute_aovs
    from ..api import make_integrator, sized_scene

    cfg = dataclasses.replace(base, method="pt", spp=1, frames=1)
    aux = compute_aovs(make_integrator(sized_scene(scene, cfg), cfg), ("albedo", "normal"), AOV_SAMPLES)
    albedo = np.clip(aux["albedo"], 0.0, 1.0).astype(np.float32)
    normal = aux["normal"].astype(np.float32)
    for m in results:
        color = np.clip(np.nan_to_num(m.last_frame), 0.0, None).astype(np.float32)
        m.denoised = np.asarray(pyoidn.denoise(color, albedo, normal, hdr=True, clean_aux=True), np.float32)
        m.metrics["relmse_denoised_frame"] = metrics.relmse(m.denoised, reference.image)
