"""The path tracer at another method's frame time: the fair per-frame baseline.

A ReSTIR frame costs several path-tracer frames at 1 spp; per frame, the path tracer at equal
time gets the samples per pixel that fit in the other method's frame. A frame's time is not
proportional to its samples: camera set-up, launches and the film cost the same at any spp, and
at small sizes that is a large part of a 1-spp frame. So the time is fitted as a + b * spp from
two probes (1 spp and an spp near the longest target), and a frame of t ms is worth (t - a) / b
samples; t / t_1spp would give the path tracer too few whenever a > 0.

That worth is rarely whole: a ReSTIR frame of 1.46 path-tracer samples is neither the path tracer
at 1 spp nor at 2, and between the two the path tracer's error changes by about 1.4x. So the
path tracer is rendered at the whole spp on both sides (`bracket`) and the headline interpolates
its error between them (headline.py); rounding instead moved close comparisons by up to that
factor (docs/changelog.md#restir-compare-the-path-tracer-at-the-exact-frame-time).
"""
import dataclasses
import math
import statistics
import time

PROBE_FRAMES = 5    # timed frames per probe (the median is kept), after one untimed frame
MAX_PROBE_SPP = 64


@dataclasses.dataclass
class FrameTimeFit:
    """ms per frame = fixed_ms + per_spp_ms * spp, from the two probes' (spp, ms)."""
    fixed_ms: float
    per_spp_ms: float
    probes: list

    def spp_at(self, ms: float) -> float:
        """The samples per pixel a frame of `ms` is worth (at least 1)."""
        return max(1.0, (ms - self.fixed_ms) / self.per_spp_ms)

    def bracket(self, ms: float) -> tuple:
        """The whole spp on both sides of `spp_at(ms)` (one when it is whole)."""
        s = self.spp_at(ms)
        return tuple(sorted({math.floor(s), math.ceil(s)}))

    def to_dict(self) -> dict:
        return {"fixed_ms": self.fixed_ms, "per_spp_ms": self.per_spp_ms,
                "probes": [{"spp": s, "ms": t} for s, t in self.probes]}


def _frame_ms(scene, config) -> float:
    from ..api import make_integrator, sized_scene

    integ = make_integrator(sized_scene(scene, config), config)
    integ.render_frame(0)  # kernels loaded, caches warm
    times = []
    for f in range(1, PROBE_FRAMES + 1):
        t = time.perf_counter()
        integ.render_frame(f)
        times.append(1e3 * (time.perf_counter() - t))
    return statistics.median(times)


def fit_frame_time(scene, base, longest_ms: float, settings: dict | None = None) -> FrameTimeFit:
    """Probe the path tracer (`settings` on `base`) at 1 spp and at the spp a 1-spp frame's time
    suggests for `longest_ms` (at least 2, at most MAX_PROBE_SPP), and fit the line through both.
    The per-spp cost is kept positive (timing noise on a tiny image could tilt it)."""
    cfg = dataclasses.replace(base, method="pt", settings=dict(settings or {}), spp=1)
    t1 = _frame_ms(scene, cfg)
    high = min(MAX_PROBE_SPP, max(2, round(longest_ms / max(t1, 1e-6))))
    th = _frame_ms(scene, dataclasses.replace(cfg, spp=high))
    per_spp = max((th - t1) / (high - 1), 1e-3 * t1)
    return FrameTimeFit(t1 - per_spp, per_spp, [(1, t1), (high, th)])
