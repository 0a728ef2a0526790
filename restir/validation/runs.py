"""Independent runs of a method and their comparison with a reference method.

Independence comes only from separate runs: each run has its own seed and empty history, and
its statistic is its own average image over T frames (pixels and frames within one run are
correlated through reuse and never treated as independent samples).
"""
import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from ..fanout import run_tasks
from ..config import RenderConfig
from .check import compare
from .stats import RGBZTest


class ImageBatches:
    """K independent estimates of one image (K runs of a renderer, this one's or any other's);
    per-pixel moments over them in float64.

    Exposes `image` (mean over the estimates), `batch_variance_of_mean` (variance of that mean),
    `batch_skewness`, `batch_excess_kurtosis`, `frames` (= K, for degrees of freedom) and
    `batches` (K, H, W, 3): the interface the z-tests read.
    """

    def __init__(self, images):
        images = [np.asarray(x, np.float64)[..., :3] for x in images]
        runs = len(images)
        if runs < 2:
            from ..config import ConfigError

            raise ConfigError("at least 2 independent runs are needed")
        shapes = {x.shape for x in images}
        if len(shapes) != 1:
            from ..config import ConfigError

            raise ConfigError(f"the images differ in size: {', '.join(sorted(str(s[1]) + 'x' + str(s[0]) for s in shapes))}")
        sums = np.zeros((4,) + images[0].shape)
        for x in images:
            sums += (x, x ** 2, x ** 3, x ** 4)
        s1, s2, s3, s4 = (v / runs for v in sums)
        var = np.maximum(s2 - s1 * s1, 0.0)
        self.frames = runs
        self.batches = np.stack(images).astype(np.float32)  # (K, H, W, 3): one independent estimate per run
        self.image = s1
        self.batch_variance_of_mean = var * runs / (runs - 1) / runs
        with np.errstate(divide="ignore", invalid="ignore"):
            self.batch_skewness = np.where(var > 0, (s3 - 3 * s1 * s2 + 2 * s1 ** 3) / var ** 1.5, 0.0)
            m4 = s4 - 4 * s1 * s3 + 6 * s1 * s1 * s2 - 3 * s1 ** 4
            self.batch_excess_kurtosis = np.where(var > 0, m4 / var ** 2 - 3.0, 0.0)


# The settings that make a method biased when changed from the value given here (explicit
# switches, each documented as biased): the harness refuses them like a fault injection.
BIASED_SWITCHES = {"temporal.previous_scene": True}


class IndependentRuns(ImageBatches):
    """K runs of `config` (seeds seed0, seed0+1, ...), each run's statistic its average image
    (see ImageBatches), and `counters`: the renders' event counters summed over runs (non-finite
    values, zero-weight candidates, failed shifts).

    The harness tests the unbiased build only: a render whose `debug.mutation` setting is not
    "none" (fault injection), or with a biased switch on (BIASED_SWITCHES), is refused unless
    `allow_mutation` is set (the power checks, and measuring the switch's bias).
    """

    def __init__(self, scene, config: RenderConfig, runs: int, seed0: int = 0, allow_mutation: bool = False,
                 workers: int = 1, ray: str | None = None, per_frame: bool = False):
        """per_frame: each run's statistic is its frames side by side (an (H, T W) image) rather than
        their average, so that every frame of an animated scene is tested against its own
        reference (frame t of the reference's runs)."""
        if runs < 2:
            from ..config import ConfigError

            raise ConfigError("at least 2 independent runs are needed")
        mutation = config.settings.get("debug.mutation", "none")
        if mutation != "none" and not allow_mutation:
            raise AssertionError(f"debug.mutation={mutation} is a biased fault injection; the harness tests "
                                 "the unbiased build only")
        for key, unbiased in BIASED_SWITCHES.items():
            value = config.settings.get(key, unbiased)
            if str(value).lower() != str(unbiased).lower() and not allow_mutation:
                raise AssertionError(f"{key}={value} is a biased switch; the harness tests the unbiased build only")
        self.stats = []
        self.counters: dict[str, int] = {}
        images = []
        if per_frame:
            config = dataclasses.replace(config, keep_frames=True)
        configs = [dataclasses.replace(config, seed=seed0 + k) for k in range(runs)]
        for k, r in enumerate(run_tasks([(scene, cfg) for cfg in configs], workers=workers, ray=ray)):
            self.stats.append(r.stats)
            for name, n in r.stats.get("counters", {}).items():
                if name.startswith("nonfinite") and n:
                    raise AssertionError(f"{n} non-finite values ({name}) in run {k}: never acceptable "
                                         "(docs/validation.md#harness-rules)")
                self.counters[name] = self.counters.get(name, 0) + n
            images.append(np.concatenate(list(r.frame_images), axis=1) if per_frame else r.image)
        super().__init__(images)


DEFAULT_MAX_MDB = 0.05  # a pass must rule out relative biases above 5% (restir validate --max-mdb)


@dataclass
class Validation:
    report: RGBZTest
    tested: ImageBatches
    reference: ImageBatches | None  # None: an exact (converged) reference
    max_mdb: float = DEFAULT_MAX_MDB  # the largest minimum detectable bias a pass may have (a fraction)

    @property
    def verdict(self) -> str:
        """"pass", "fail", or "inconclusive": no failure, but either the pixel statistics are too
        skewed to judge, or the test could not have detected a bias of `max_mdb` (its minimum
        detectable bias, at 80% power, is larger). A detected bias fails whatever the MDB."""
        if not self.report.passed:
            return "fail"
        return "pass" if self.reason is None else "inconclusive"

    @property
    def reason(self) -> str | None:
        """Why a verdict without failure is not a pass (None when it is)."""
        if not self.report.passed:
            return None
        if not all(r.pixel_conclusive for r in self.report.reports):
            return "pixel statistics too skewed to judge"
        if not all(r.tile_conclusive for r in self.report.reports):
            return "tile statistics too skewed to judge"
        mdb = self.report.mdb
        if not mdb <= self.max_mdb:  # also NaN
            need = self.runs_needed
            more = f"; about {need} runs would bring it there" if need else ""
            return (f"minimum detectable bias {100 * mdb:.3g}% is above the bound {100 * self.max_mdb:.3g}%: "
                    f"a bias that size could have gone unseen{more}")
        return None

    @property
    def runs_needed(self) -> int | None:
        """Runs that would bring the MDB to `max_mdb` with the same frames and spp (both sides
        scaled alike): the MDB falls as 1/sqrt(runs), so runs * (mdb / max_mdb)^2, rounded up
        (at least the runs made). None when the MDB is not finite."""
        mdb, runs = self.report.mdb, self.tested.frames
        if not (math.isfinite(mdb) and self.max_mdb > 0):
            return None
        return max(runs, math.ceil(runs * (mdb / self.max_mdb) ** 2))

    def zmap(self) -> np.ndarray:
        return self.report.zmap()


def validate(scene, config: RenderConfig, runs: int, reference: RenderConfig, reference_runs: int | None = None,
             tile: int = 8, alpha: float = 1e-3, max_mdb: float = DEFAULT_MAX_MDB, workers: int = 1,
             ray: str | None = None) -> Validation:
    """Compare `config` against `reference` (both noisy; Welch z per channel,
    docs/validation.md#the-z-tests-image-tile-and-pixel), on an animated scene frame by frame
    (each run's frames side by side: IndependentRuns per_frame);
    a pass needs a minimum detectable bias of at most `max_mdb` (see Validation.verdict). The runs
    are independent tasks: `workers` local processes or a Ray cluster (restir/fanout.py)."""
    per_frame = scene.animation is not None  # every frame against the same frame of the reference's runs
    if per_frame and (workers > 1 or ray is not None):
        from ..scene.animation import check_picklable

        check_picklable(scene)
    tested = IndependentRuns(scene, config, runs, seed0=1000, workers=workers, ray=ray, per_frame=per_frame)
    ref = IndependentRuns(scene, reference, reference_runs or runs, seed0=900_000, workers=workers, ray=ray,
                          per_frame=per_frame)
    rep = compare(tested, ref.image, ref.batch_variance_of_mean, other=ref, tile=tile, alpha=alpha)
    return Validation(rep, tested, ref, max_mdb)


def validate_images(images, reference_images=None, reference=None, reference_var=0.0, tile: int = 8,
                    alpha: float = 1e-3, max_mdb: float = DEFAULT_MAX_MDB) -> Validation:
    """The harness on images made by any renderer: `images`, K >= 2 independent runs of the
    tested renderer (each its own average image), against either `reference_images` (K' >= 2
    independent runs of the reference) or `reference`, one converged image, with the per-pixel
    variance of its mean in `reference_var` (0: taken as exact)."""
    tested = ImageBatches(images)
    if reference_images is not None:
        ref = ImageBatches(reference_images)
        if ref.image.shape != tested.image.shape:
            from ..config import ConfigError

            raise ConfigError(f"the reference images are {ref.image.shape[1]}x{ref.image.shape[0]}, the tested "
                              f"{tested.image.shape[1]}x{tested.image.shape[0]}")
        rep = compare(tested, ref.image, ref.batch_variance_of_mean, other=ref, tile=tile, alpha=alpha)
        return Validation(rep, tested, ref, max_mdb)
    ref_image = np.asarray(reference, np.float64)[..., :3]
    if ref_image.shape != tested.image.shape:
        from ..config import ConfigError

        raise ConfigError(f"the reference is {ref_image.shape[1]}x{ref_image.shape[0]}, the tested images "
                          f"{tested.image.shape[1]}x{tested.image.shape[0]}")
    rep = compare(tested, ref_image, reference_var, tile=tile, alpha=alpha)
    return Validation(rep, tested, None, max_mdb)
