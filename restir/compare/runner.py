"""`compare`: several methods on one scene with the same budget, measured against a reference.

Budgets. Equal time: each method renders frames until its wall time (frames only: kernel
compilation is done beforehand, on a throwaway 16x16 render of the same configuration) reaches
the budget; the frame that crosses it is kept. Equal samples: each method renders N samples per
pixel in total (N / spp frames). Otherwise every method renders `frames` frames.

Both conventions of the field are reported. Per frame: the mean relMSE of single frames after
`warmup` frames (what a real-time application shows). Accumulated: the average of every frame
rendered within the budget (what an offline user gets). The bias check (image-mean ratio and its
z, restir.validation's image-level test) uses batch means of consecutive frames (frames.py),
since temporal reuse correlates consecutive frames.

What a denoiser sees (structure.py, denoise.py): the error's correlation factor at block sizes 2
to 16 and its temporal correlation, per frame after the warm-up; the radial correlation from
independent runs at one frame index; and, with `denoise`, the per-frame error after Open Image
Denoise. At equal time the path tracer is also rendered at each other method's frame time
(equal_time.py), the fair per-frame baseline, and the headline (headline.py) gives each method's
factor against it, raw and denoised.
"""
import dataclasses
import time

import numpy as np

from ..config import ConfigError, RenderConfig
from ..limits import MAX_FRAMES
from . import metrics
from . import structure
from .config import CompareConfig
from .frames import FrameStats
from .reference import Reference, load_reference_file, path_traced_reference

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
            METHODS[name].Settings.from_overrides(settings)  # unknown keys and bad values, before any work
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
    radial: dict | None = None          # radial correlation: radii, values, standard errors, runs, frame
    frame_time_of: list = dataclasses.field(default_factory=list)  # the path tracer on either side of these methods' frame time
    denoise_subset: list | None = None  # the frames the denoised metrics are over (indices)
    frame_subset: list | None = dataclasses.field(default=None, repr=False)  # those frames (not in the JSON)


_IMAGES = ("image", "last_frame", "denoised", "frame_subset")


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
    frame_time_fit: dict | None = None  # the path tracer's ms per frame as a + b spp, each method's spp (equal_time.py)
    headline: list = dataclasses.field(default_factory=list)  # headline.py: factors against the path tracer

    def to_dict(self) -> dict:
        """Everything but the images, as plain JSON data."""
        return {"scene": self.scene, "width": self.width, "height": self.height, "budget": self.budget,
                "warmup": self.warmup, "reference": self.reference.source, "notes": list(self.notes),
                "interrupted": self.interrupted, "frame_time_fit": self.frame_time_fit,
                "reference_relmse": self.reference.own_relmse(),
                "headline": [dict(h) for h in self.headline],
                "methods": [{k: v for k, v in dataclasses.asdict(m).items() if k not in _IMAGES}
                            for m in self.methods]}


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
         "mean_mdb": mdb, "frames_after_warmup": len(after), "ms_per_frame": 1e3 * seconds / n,
         **frames.structure()}
    indices, subset = frames.denoise_frames()
    return MethodResult(label, config.method, dict(config.settings), config.spp, n, seconds, image.astype(np.float32),
                        list(frame_seconds), frames.frame_err, frames.acc_err, m, stats, frames.last.astype(np.float32),
                        denoise_subset=indices, frame_subset=subset)


def _compile_first(scene, config: RenderConfig):
    """Load (compile if needed) the method's kernels on a 16x16 render, so that no budget is spent
    compiling."""
    from ..fanout import warm_kernels

    warm_kernels([(scene, config)])


def _config(base: RenderConfig, spec: MethodSpec) -> RenderConfig:
    return dataclasses.replace(base, method=spec.method, settings=dict(spec.settings), spp=spec.spp or 1)


def _run_method(scene, spec: MethodSpec, base: RenderConfig, reference: Reference, budget, warmup, progress):
    from ..api import make_integrator, sized_scene

    kind, amount = budget
    config = _config(base, spec)
    frames_max = -(-amount // config.spp) if kind == "spp" else amount if kind == "frames" else base.frames
    _compile_first(scene, config)
    integ = make_integrator(sized_scene(scene, config), config)
    frames, frame_seconds = FrameStats(reference, warmup), []
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
        configs.append(dataclasses.replace(_config(base, spec), frames=frames, keep_frames=True))
    renders = run_tasks([(scene, c) for c in configs], workers=workers, ray=ray,
                        progress=(lambda done, total: progress("methods", done / total)) if progress else None)
    out = []
    for spec, cfg, r in zip(specs, configs, renders):
        fs = FrameStats(reference, warmup)
        for x in r.frame_images:
            fs.add(x)
        ms = r.stats["ms_per_frame"]
        out.append(measure(spec.label, cfg, fs, [ms * 1e-3 * (i + 1) for i in range(fs.count)], reference, warmup,
                           r.stats))
    return out


def _run_in_turn(scene, specs, base, reference, budget, warmup, progress, results, notes) -> bool:
    """Render `specs` one after another into `results`; False when Ctrl-C stopped them (a note
    says which finished, which was stopped and which never ran)."""
    done = []
    for s in specs:
        try:
            done.append(_run_method(scene, s, base, reference, budget, warmup, progress))
        except KeyboardInterrupt:
            done.append(None)
        if done[-1] is None or done[-1].interrupted:
            break
    finished = [r for r in done if r is not None]
    results.extend(finished)
    if len(finished) < len(specs) or (finished and finished[-1].interrupted):
        notes.append("interrupted (Ctrl-C): " + ", ".join(
            f"{r.label} {'stopped after ' + str(r.frames) + ' frames' if r.interrupted else 'complete'}"
            for r in finished) + "; not run: " + (", ".join(s.label for s in specs[len(finished):]) or "none"))
        return False
    return True


def compare(scene, methods, config: CompareConfig | None = None, *, progress=None, **options) -> Comparison:
    """Render every method in `methods` (MethodSpec or 'name:key=value,...' strings) on `scene`
    with the same budget and measure each against the reference.

    config: a CompareConfig (the budget, reference, size, denoising, where renders run); or its
    fields as keyword `options` (compare(scene, ["pt"], frames=4)), or both (the options then
    replace those fields). `progress(label, fraction)` is called after every frame (label
    "reference" while the reference renders).

    Each MethodResult.metrics holds relmse_frame (mean over frames after `warmup`),
    relmse_accumulated, mape, flip (None without flip-evaluator), mean_ratio with mean_z and
    mean_mdb (the image-level bias test; None with fewer than 2 blocks), ms_per_frame,
    correlation_factor (per block size, mean over the frames after `warmup`) and
    temporal_correlation (structure.py). With `denoise`: relmse_denoised_frame and
    flip_denoised_frame, means over the denoised frames, with relmse_frame_subset and flip_frame
    of the same frames raw; MethodResult.denoised is the last frame denoised.
    """
    from ..api import check_device, sized_scene
    from ..fanout import default_workers

    unknown = set(options) - {f.name for f in dataclasses.fields(CompareConfig)}
    if unknown:
        raise TypeError(f"compare() got unknown options {sorted(unknown)} (CompareConfig's fields are the options)")
    c = dataclasses.replace(config or CompareConfig(), **options)
    specs = [m if isinstance(m, MethodSpec) else MethodSpec.parse(m) for m in methods]
    if not specs:
        raise ConfigError("compare needs at least one --method")
    if len({s.label for s in specs}) != len(specs):
        raise ConfigError("the same --method is given twice")
    c.validate()
    from ..scene.animation import refuse_for_one_reference

    refuse_for_one_reference(scene, "compare")
    method_workers = c.workers or (1 if c.equal_time is not None else min(default_workers(), len(specs)))
    fan_out = c.equal_time is None and (c.ray is not None or method_workers > 1)
    from ..integrators import METHODS

    notes = []
    max_depth = c.max_depth
    fixed = {METHODS[s.method].FIXED_MAX_DEPTH for s in specs} - {None}
    for depth in fixed:  # restir-di computes max_depth 2 only: everything is compared at that depth
        if max_depth is not None and max_depth != depth:
            raise ConfigError(f"max_depth {max_depth}: "
                              f"{', '.join(s.label for s in specs if METHODS[s.method].FIXED_MAX_DEPTH is not None)} "
                              f"computes max_depth {depth} only")
        if max_depth is None:
            notes.append(f"every method and the reference at max_depth {depth}, the only depth of "
                         + ", ".join(s.label for s in specs if METHODS[s.method].FIXED_MAX_DEPTH is not None))
        max_depth = depth
    # at equal time the budget ends the frames; their count only has to be within the limits
    base = RenderConfig(frames=MAX_FRAMES if c.equal_time is not None else c.frames, width=c.width, height=c.height,
                        max_depth=max_depth, seed=c.seed, device=c.device, jitter=c.jitter)
    base.validate()
    check_device(base)
    sized = sized_scene(scene, base)
    w, h = sized.camera.width, sized.camera.height
    base = dataclasses.replace(base, width=w, height=h)
    if c.reference == "mitsuba":
        from .reference import mitsuba_reference

        ref = mitsuba_reference(scene, c.scene_file, c.defines, c.reference_spp,
                                dataclasses.replace(base, width=c.width, height=c.height, max_depth=max_depth))
    elif c.reference is not None:
        ref = load_reference_file(c.reference, w, h)
    else:
        ref = path_traced_reference(scene, c.reference_spp, base,
                                    progress=(lambda done, total: progress("reference", done / total)) if progress else None)
    budget, text = c.budget()
    warmup = c.warmup
    comparison = Comparison(scene.name, w, h, text, warmup, ref, [], notes)
    own = ref.own_relmse()
    if own is not None:
        notes.append(f"the reference's own relMSE is about {own:.3g} (from its {len(ref.blocks)} independent "
                     "blocks); every relMSE here includes it, so values near it (denoised frames, long "
                     "accumulations) are not resolved: raise --reference-spp")
    if fan_out:
        comparison.methods = _fan_out(scene, specs, base, ref, budget, warmup, method_workers, c.ray, progress)
        complete = True
    else:
        complete = _run_in_turn(scene, specs, base, ref, budget, warmup, progress, comparison.methods, notes)
        if not comparison.methods:  # Ctrl-C before the first method's first frame: nothing to keep
            raise KeyboardInterrupt
    if complete and c.equal_time is not None and c.match_frame_time:
        complete = _match_frame_time(scene, specs, base, ref, budget, warmup, progress, comparison)
    if complete and c.correlation_runs:
        complete = _radial(scene, comparison.methods, base, warmup, c.correlation_runs, c.workers, c.ray, progress,
                           notes)
    if complete and c.denoise:
        complete = _denoise(scene, base, comparison.methods, ref, progress, notes)
    comparison.interrupted = not complete
    from .headline import headline

    comparison.headline = headline(comparison)
    return comparison


def _match_frame_time(scene, specs, base, reference, budget, warmup, progress, comparison) -> bool:
    """The path tracer at the whole spp on both sides of each non-pt method's frame time (same
    budget), appended to the comparison's methods; a user's `pt` entry at such an spp is used as
    it is. Each method's frame in path-tracer spp goes to `frame_time_fit["spp_of"]`."""
    from .equal_time import fit_frame_time

    others = [m for m in comparison.methods if m.method != "pt"]
    if not others:
        return True
    given = [s for s in specs if s.method == "pt"]
    settings = dict(given[0].settings) if given else {}
    if progress:
        progress("fitting the path tracer's frame time", 0.0)
    try:
        fit = fit_frame_time(scene, base, max(m.metrics["ms_per_frame"] for m in others), settings)
    except KeyboardInterrupt:
        comparison.notes.append("interrupted (Ctrl-C) while fitting the path tracer's frame time: no path "
                                "tracer at the methods' frame time")
        return False
    comparison.frame_time_fit = fit.to_dict()
    comparison.frame_time_fit["spp_of"] = {m.label: fit.spp_at(m.metrics["ms_per_frame"]) for m in others}
    wanted = {}  # the path tracer at the whole spp on both sides of each method's frame
    for m in others:
        for spp in fit.bracket(m.metrics["ms_per_frame"]):
            wanted.setdefault(spp, []).append(m.label)
    new = []
    for spp, labels in sorted(wanted.items()):
        same = [r for r in comparison.methods if r.method == "pt" and r.spp == spp and r.settings == settings]
        if same:
            same[0].frame_time_of += labels
            continue
        label = "pt:" + ",".join([f"{k}={v}" for k, v in settings.items()] + [f"spp={spp}"])
        new.append(MethodSpec(label, "pt", settings, spp))
    before = len(comparison.methods)
    complete = _run_in_turn(scene, new, base, reference, budget, warmup, progress, comparison.methods,
                            comparison.notes)
    for r in comparison.methods[before:]:
        r.frame_time_of = wanted[r.spp]
    comparison.notes.append(
        "the path tracer at each method's frame time: ms per frame = {:.2f} + {:.3f} spp (probes {}); ".format(
            fit.fixed_ms, fit.per_spp_ms, ", ".join(f"{s} spp {t:.1f} ms" for s, t in fit.probes))
        + "; ".join(f"{label}: {spp:.2f} spp" for label, spp in comparison.frame_time_fit["spp_of"].items())
        + " (the path tracer rendered at " + ", ".join(str(spp) for spp in sorted(wanted))
        + " spp, its errors interpolated between them)")
    return complete


def _radial(scene, results, base, warmup, runs, workers, ray, progress, notes) -> bool:
    """Each result's radial correlation from `runs` independent renders of warmup + 1 frames."""
    from ..fanout import last_frame_task, run_tasks

    tasks = []
    for m in results:
        cfg = dataclasses.replace(base, method=m.method, settings=dict(m.settings), spp=m.spp, frames=warmup + 1)
        tasks += [(scene, dataclasses.replace(cfg, seed=base.seed + 1 + k)) for k in range(runs)]
    try:
        frames = run_tasks(tasks, workers=workers, ray=ray, task=last_frame_task,
                           progress=(lambda d, t: progress("correlation runs", d / t)) if progress else None)
    except KeyboardInterrupt:
        notes.append("interrupted (Ctrl-C) during the correlation runs: no radial correlation")
        return False
    for i, m in enumerate(results):
        values, errors = structure.radial_correlation(np.stack(frames[i * runs:(i + 1) * runs]), structure.RADII)
        m.radial = {"radii": list(structure.RADII), "values": values, "standard_errors": errors, "runs": runs,
                    "frame": warmup}
    return True


def _denoise(scene, base: RenderConfig, results, reference: Reference, progress, notes) -> bool:
    """The measured frames (denoise.py's subset) and the last frame through OIDN."""
    from .denoise import Denoiser

    try:
        denoiser = Denoiser.for_scene(scene, base)
        for i, m in enumerate(results):
            den = [denoiser(x) for x in m.frame_subset]
            m.denoised = denoiser(m.last_frame)
            m.metrics["relmse_denoised_frame"] = float(np.mean([metrics.relmse(d, reference.image) for d in den]))
            m.metrics["relmse_frame_subset"] = float(np.mean([m.frame_relmse[k] for k in m.denoise_subset]))
            flips = [metrics.flip(d, reference.image) for d in den]
            raw_flips = [metrics.flip(x, reference.image) for x in m.frame_subset]
            m.metrics["flip_denoised_frame"] = None if None in flips else float(np.mean(flips))
            m.metrics["flip_frame"] = None if None in raw_flips else float(np.mean(raw_flips))
            m.metrics["denoised_frames"] = len(den)
            if progress:
                progress("denoising", (i + 1) / len(results))
        notes.append(f"denoised by Open Image Denoise on {denoiser.where}")
    except KeyboardInterrupt:
        notes.append("interrupted (Ctrl-C) while denoising: the denoised metrics are incomplete")
        return False
    return True
