"""What the path-reuse methods (ReSTIR PT, Suffix ReSTIR) share besides their stages: the checks
of the settings they have in common, the primary-hit layer with ReSTIR DI on it, the frame's
ReSTIR PT parameters, the ping-pong pass that counts its shifts, and the shift stats."""
import dataclasses

import numpy as np
import warp as wp

from ...device.streams import PT_MAX_CANDIDATES, PT_MAX_NEIGHBORS
from ...settings import Settings, setting
from ..base import Integrator
from ..common.primary_hits import MUTATIONS as PRIMARY_HIT_MUTATIONS, mutant_kernel, trace_primary_hits
from ..common.events import PassCounts
from ..common.gbuffer import PingPong, allocate_primary_gbuffer
from .direct_light import attach_direct_light, check_di_settings
from .params import SHIFTS, PathReuseParams

PT_MAX_DEPTH = 255  # path lengths are 8-bit fields (Bitterli's scenes ask for max_depth 65)
PT_UNBOUNDED_DEPTH = 64  # max_depth -1 renders at this depth, with a note


def summarize_shifts(shift_counts: dict) -> tuple[dict, list]:
    """Per pass, the shifts of reconnections (paths with an rc vertex) and pure replays: tried,
    succeeded and the success rate; and the passes whose shifts never succeeded ("reuse dead":
    reuse that does nothing is reported, not passed; docs/validation.md#always-on-diagnostics)."""
    shifts, dead = {}, []
    for stage, c in shift_counts.items():
        kinds = {}
        for name, (tried, ok) in (("reconnection", c[0:2]), ("replay", c[2:4])):
            kinds[name] = {"tried": int(tried), "succeeded": int(ok), "success_rate": float(ok / tried) if tried else None}
        shifts[stage] = kinds
        if c[0] + c[2] > 0 and c[1] + c[3] == 0:
            dead.append(stage)
    return shifts, dead


@dataclasses.dataclass
class PathReuseSettings(Settings):
    """The settings every path-reuse method starts with (its own follow, then rc.*, the fault
    injection and the di.* component)."""
    shift: str = setting("shift", "hybrid", "hybrid: replay to the first vertex that qualifies, then reconnect; "
                         "reconnection: at the first vertex after the path's start (ReSTIR PT: x2; Suffix ReSTIR: "
                         "after the prefix end); replay: the whole path")
    direct: str = setting("direct", "restir-di", "restir-di: direct light at the primary hit from ReSTIR DI (the "
                          "di.* settings); pt: the method's paths own every event")
    candidates: int = setting("candidates", 1, "paths traced per pixel from its start, streaming RIS over their "
                              "events, M = 1 each (ReSTIR PT: base paths at the primary hit; Suffix ReSTIR: "
                              "suffixes at the resampled prefix end)")


class PathReuseIntegrator(Integrator):
    """Base of ReSTIR PT and Suffix ReSTIR. A subclass names its spatial-reuse settings (SPATIAL:
    the attribute holding its SpatialReuseSettings) and its MUTATIONS."""

    SPATIAL = "spatial"
    DIRECT = ("restir-di", "pt")  # the direct settings the method has

    @classmethod
    def check_path_settings(cls, settings) -> None:
        """The settings every path-reuse method has: shift, direct, candidates, spatial reuse,
        the rc criteria, the fault injection, max_depth, and ReSTIR DI's."""
        from ...config import ConfigError

        s = settings
        if s.shift not in SHIFTS:
            raise ConfigError(f"shift must be one of {', '.join(SHIFTS)}")
        if s.direct not in cls.DIRECT:
            raise ConfigError(f"direct must be {' or '.join(cls.DIRECT)}")
        if not 1 <= s.candidates <= PT_MAX_CANDIDATES:
            raise ConfigError(f"candidates must be in [1, {PT_MAX_CANDIDATES}]")
        getattr(s, cls.SPATIAL).check(PT_MAX_NEIGHBORS)
        if not s.rc_near_distance >= 0.0 or not s.rc_roughness >= 0.0:
            raise ConfigError("rc.near_distance and rc.roughness must be >= 0")
        if s.debug_mutation not in cls.MUTATIONS:
            raise ConfigError(f"debug.mutation must be one of {', '.join(cls.MUTATIONS)}")
        if s.max_depth > PT_MAX_DEPTH:
            raise ConfigError(f"{cls.name} renders max_depth up to {PT_MAX_DEPTH} (or -1, as {PT_UNBOUNDED_DEPTH})")
        check_di_settings(s)

    def allocate_path_reuse(self) -> None:
        """max_depth -1 as PT_MAX_DEPTH (with a note), the spatial radius, the primary-hit layer
        (G-buffer pair, filter weights, emission) with ReSTIR DI on it, the path reservoirs
        (ping-pong pair and pass output), the sample's radiance and the shift-count scratch."""
        from .path_sample import PathReservoir

        s = self.settings
        if s.max_depth < 0:
            s.max_depth = PT_UNBOUNDED_DEPTH
            self.notes.append(f"{self.name} renders unbounded depth as max_depth {PT_UNBOUNDED_DEPTH}")
        self.spatial_radius = getattr(s, self.SPATIAL).resolve_radius(self.height)
        self.gbuffers = PingPong(allocate_primary_gbuffer(self, "gbuffer"),
                                 allocate_primary_gbuffer(self, "gbuffer_prev"))
        self.primary_weight = self.buffer("primary_weight", float)
        self.emission = self.buffer("emission", wp.vec3)
        self.reservoirs = PingPong(self.buffer(f"{self.RESERVOIRS}", PathReservoir),
                                   self.buffer(f"{self.RESERVOIRS}_prev", PathReservoir))
        self.pass_out = self.buffer(f"{self.RESERVOIRS}_pass", PathReservoir) if self.wants_pass_buffer() else None
        self.sample_L = self.buffer("sample_L", wp.vec3)
        # per-pass scratch for the stats, like `events`: shift counts in reuse passes
        self.shift_events = self.buffer("shift_events", PassCounts)
        self.shift_counts: dict = {}   # per pass: [reconnections tried, succeeded, replays tried, succeeded]
        self.prev_camera = None
        self.prev_scene = None  # the scene of the previous sample (the history's domain)
        self.current_camera = self.dscene.camera  # the camera of the sample being rendered
        # ReSTIR DI owns direct light at the primary hit (max_depth >= 2), on this method's G-buffers
        self.di = attach_direct_light(self)
        # the first vertex whose events the method resamples; paths need max_depth >= first + 2
        # (direct=nee sums x_0's events in the trace stage, which then runs from max_depth 2)
        self.first_event = 0 if s.direct == "pt" else 1
        self.resamples = s.max_depth >= (2 if s.direct == "nee" else self.first_event + 2)

    def wants_pass_buffer(self) -> bool:
        """Whether a reuse pass runs while the history is still to be read, so that its output
        needs a third path-reservoir buffer. Without one, every pass writes into the history's
        buffer (Integrator.reuse_pass): a method's passes then run only after its history was read."""
        return False

    def pt_params(self, frame: int, sample: int, near_distance: float, temporal_cap: float) -> PathReuseParams:
        """The frame's ReSTIR PT parameters (the path samples' shift, rc criteria and reuse)."""
        s = self.settings
        p = PathReuseParams()
        p.seed = wp.uint32(s.seed & 0xFFFFFFFF)
        p.frame = wp.uint32(frame)
        p.sample = sample
        p.candidates = int(s.candidates)
        p.max_depth = int(s.max_depth)
        p.first_event = self.first_event
        p.direct_nee = int(s.direct == "nee")
        p.expected_out = 0
        p.shift = int(SHIFTS[s.shift])
        p.near_distance = float(near_distance)
        p.rough_threshold = float(s.rc_roughness)
        p.temporal_cap = float(temporal_cap)
        p.spatial_round = 0
        p.spatial_k = int(getattr(s, self.SPATIAL).neighbors)
        p.spatial_radius = float(self.spatial_radius)
        return p

    def count_shifts(self, stage: str) -> None:
        """The pass's shift counts (in `shift_events`) summed on the device, read once per frame."""
        self.tally.add(("shifts", stage), self.shift_events)

    def take_tally(self, key, sums: np.ndarray) -> None:
        if key[0] == "shifts":
            acc = self.shift_counts.setdefault(key[1], np.zeros(4, np.int64))
            acc += sums
        else:
            super().take_tally(key, sums)

    def reuse_pass(self, stage: str, kernel, inputs: list, in_place: bool = False, counts: tuple | None = None,
                   parts: int | None = None, scratch: tuple = ()) -> None:
        """The base class's ping-pong pass, with the per-pixel counts it writes to `shift_events`
        summed for the stats: its shifts, or the tally key `counts` (a pass that counts something
        else, such as the MCMC stage's proposals). parts: a pass of that many launches (the kernel
        adds its counts up over them), scratch: buffers it writes before `shift_events`."""
        super().reuse_pass(stage, kernel, inputs, (*scratch, self.shift_events), in_place, parts)
        if counts is None:
            self.count_shifts(stage)
        else:
            self.tally.add(counts, self.shift_events)

    def render_sample(self, frame: int, sample: int, camera):
        """The primary hits and the direct light (ReSTIR DI, or the emission seen directly), the
        method's resampling passes and output (`resample_sample`), then this sample's final
        reservoirs and primary hits become the next one's history."""
        self.current_camera = camera
        if self.di is not None:
            self.di.current_camera = camera
        mutation = self.settings.debug_mutation
        mutant = mutant_kernel(mutation) if mutation in PRIMARY_HIT_MUTATIONS else None
        trace_primary_hits(self, camera, wp.uint32(self.settings.seed & 0xFFFFFFFF), wp.uint32(frame), sample,
                           int(bool(self.settings.hide_emitters)), self.gbuffers.current, self.primary_weight,
                           self.emission, mutant)
        direct = self.emission
        if self.di is not None:
            self.di.resample_and_shade(frame, sample)
            direct = self.di.sample_L
        L = self.resample_sample(frame, sample, direct) if self.resamples else direct
        self.reservoirs.swap()
        self.swap_history()
        if self.di is not None:
            self.di.end_sample(camera)
        self.gbuffers.swap()
        self.prev_camera = camera
        self.prev_scene = self.dscene.scene
        return L

    def resample_sample(self, frame: int, sample: int, direct):
        """The method's passes for one sample after the primary hits; the sample's radiance (a
        device array, one vec3 per pixel)."""
        raise NotImplementedError

    def swap_history(self) -> None:
        """The method's own buffers that become history at the end of a sample (besides the path
        reservoirs, the G-buffers and ReSTIR DI's)."""

    def stats(self) -> dict:
        """The base stats (ReSTIR DI's rays among them: the component shares stage_rays) and the
        reuse diagnostics (docs/validation.md#always-on-diagnostics): the shifts per pass and the
        reuse-dead passes."""
        out = super().stats()
        out["shifts"], out["reuse_dead"] = summarize_shifts(self.shift_counts)
        return out
