"""CompareConfig: everything a comparison is asked for except the scene and the methods (the
budget, the reference, the image, what a denoiser sees, where the renders run), checked before
any work."""
import dataclasses

from ..config import ConfigError
from ..limits import MAX_RUNS, MAX_SECONDS


@dataclasses.dataclass
class CompareConfig:
    """Options of `restir.compare.compare` (and `restir compare`, one field per option).

    reference: an image file (EXR, PNG, NPY) of the compared size, None for the path tracer at
    `reference_spp`, or "mitsuba" for Mitsuba 3 at `reference_spp` on `scene_file` (the XML the
    scene was loaded from, with its `defines`); both cached, see reference.py.

    Budget: `equal_time` seconds of frames per method, or `equal_spp` samples per pixel in total,
    or `frames` frames each (also the cap on frames under equal time, when given explicitly as
    more than the default). `warmup`: frames before the per-frame error is measured.

    match_frame_time (equal time only): the path tracer is also rendered, with the same budget, at
    each other method's frame time (spp from a fit of its frame time, equal_time.py; methods whose
    frame times give the same spp share one), the per-frame baseline of `Comparison.headline`.
    Its settings are those of the first `pt` method given, if any.

    correlation_runs K >= 3 (0: none): every method (the matched path tracers too) is also rendered
    K times with seeds seed + 1 .. seed + K for warmup + 1 frames; MethodResult.radial has the
    radial correlation of those last frames (structure.radial_correlation).

    denoise: the frames after the warm-up (all, or an evenly spaced subset of 9 to 16: denoise.py)
    and the last frame are denoised by Intel Open Image Denoise (the `pyoidn` package, the
    `denoise` extra) with albedo and normal guides (restir/aov.py), the real-time use of ReSTIR.

    jitter False: every method and the path-traced reference put their primary rays through the
    pixel centres (RenderConfig.jitter; the Suffix ReSTIR paper's setting); a Mitsuba reference
    cannot (Mitsuba always samples the pixel), so that pair is refused.

    workers (default: one per core, and at equal time 1 for the methods) > 1 or ray: independent
    renders run as tasks (restir/fanout.py): the methods (equal samples or frames only: an
    equal-time comparison needs each method alone on the machine; their ms per frame are then
    measured under each other's load) and the correlation runs.
    """
    reference: str | None = None
    reference_spp: int = 1024
    equal_time: float | None = None
    equal_spp: int | None = None
    frames: int = 16
    warmup: int = 4
    seed: int = 0
    width: int | None = None
    height: int | None = None
    max_depth: int | None = None
    device: str = "cpu"
    denoise: bool = False
    correlation_runs: int = 8
    match_frame_time: bool = True
    workers: int | None = None
    ray: str | None = None
    scene_file: str | None = None
    defines: dict | None = None
    jitter: bool = True

    def validate(self) -> None:
        """Refuse a comparison that cannot run, before anything renders."""
        if self.equal_time is not None and self.equal_spp is not None:
            raise ConfigError("give --equal-time or --equal-spp, not both")
        if self.equal_time is not None and not 0 < self.equal_time <= MAX_SECONDS:
            raise ConfigError(f"--equal-time must be in (0, {MAX_SECONDS}] seconds (got {self.equal_time})")
        if self.equal_spp is not None and self.equal_spp < 1:
            raise ConfigError("--equal-spp must be >= 1")
        if self.correlation_runs > MAX_RUNS:
            raise ConfigError(f"--correlation-runs must be at most {MAX_RUNS} (got {self.correlation_runs})")
        if self.correlation_runs != 0 and self.correlation_runs < 3:
            raise ConfigError(f"--correlation-runs {self.correlation_runs}: the radial correlation needs at least 3 "
                              "independent runs (0: none)")
        if self.workers is not None and self.workers < 1:
            raise ConfigError("--workers must be >= 1")
        if self.equal_time is not None and (self.ray is not None or (self.workers or 1) > 1) \
                and not self.correlation_runs:
            raise ConfigError("--equal-time renders the methods one after another (each alone on the machine, or "
                              "its time would include the others' load); --workers and --ray apply to equal "
                              "samples or frames, and to the correlation runs")
        if not self.jitter and self.reference == "mitsuba":
            raise ConfigError("--no-jitter with --reference mitsuba: Mitsuba 3 always samples the pixel area, so "
                              "its image is not the radiance at the pixel centres; use the path-traced reference")
        if self.frames < 1 or self.warmup < 0 or self.reference_spp < 1:
            raise ConfigError("frames and reference spp must be >= 1, warmup >= 0")
        if self.denoise:
            from .denoise import require_oidn

            require_oidn()

    def budget(self) -> tuple:
        """(kind, value) of the budget and its sentence for the report."""
        if self.equal_time is not None:
            return ("time", self.equal_time), f"equal time: {self.equal_time:g} s of frames per method"
        if self.equal_spp is not None:
            return ("spp", self.equal_spp), f"equal samples: {self.equal_spp} spp per pixel per method"
        return ("frames", self.frames), f"{self.frames} frames per method"
