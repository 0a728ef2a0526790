"""ReSTIR PT as a pipeline of stages: primary hits, ReSTIR DI (direct light at the primary hit,
unless direct=pt), trace and initial RIS, temporal reuse, spatial reuse rounds, shading.

render_frame is the table of contents; each stage is one kernel in its own file.
"""
import numpy as np
import warp as wp

from ...device.streams import MAX_SPATIAL_ROUNDS, PT_MAX_CANDIDATES, PT_MAX_NEIGHBORS
from ...film import PixelMoments
from ..base import Integrator
from ..common.gbuffer import PingPong, allocate_gbuffer
from ..common.primary_hits import primary_hits_kernel
from ..common.reuse_domains import resolve_spatial_radius
from ..restir_di.component import DI_SETTINGS, DI_SETTINGS_DOC, attach_direct_light, check_di_settings
from .params import SHIFTS, PTRParams
from .path_sample import PathReservoir
from .s1_initial import initial_kernel, make_initial_kernel
from .s2_temporal import make_temporal_kernel, temporal_kernel
from .s3_spatial import make_spatial_kernel, spatial_kernel
from .s4_shade import shade_kernel
from .shift import MUTATIONS as SHIFT_MUTATIONS
from .shift import make_shift

# Fault injections for the mutation tests (TESTING.md 5.11), each a build of the stage kernels
# (or, for the race, of the pipeline) that the harness refuses unless asked; the shipped
# kernels are built with none of them.
MUTATIONS = ("none", *SHIFT_MUTATIONS, "m_per_event", "drop_failed_shifts", "spatial_in_place")
_mutant_kernels: dict = {}

PT_MAX_DEPTH = 64  # max_depth -1 renders at this depth (path lengths are 8-bit fields)


def stage_kernels(mutation: str) -> tuple:
    """(initial, temporal, spatial) kernels of a build: the shipped ones, or a mutation's."""
    if mutation in ("none", "spatial_in_place"):
        return initial_kernel, temporal_kernel, spatial_kernel
    if mutation not in _mutant_kernels:
        module = f"restir_pt_{mutation}"
        if mutation in SHIFT_MUTATIONS:
            shift = make_shift(mutation)
            kernels = (initial_kernel, make_temporal_kernel(shift, module=module),
                       make_spatial_kernel(shift, module=module))
        elif mutation == "m_per_event":
            kernels = (make_initial_kernel(m_per_event=True), temporal_kernel, spatial_kernel)
        else:  # drop_failed_shifts
            kernels = (initial_kernel, make_temporal_kernel(drop_failed=True, module=module),
                       make_spatial_kernel(drop_failed=True, module=module))
        _mutant_kernels[mutation] = kernels
    return _mutant_kernels[mutation]


def summarize_shifts(shift_counts: dict) -> tuple[dict, list]:
    """Per pass, the shifts of reconnections (paths with an rc vertex) and pure replays: tried,
    succeeded and the success rate; and the passes whose shifts never succeeded ("reuse dead":
    reuse that does nothing is reported, not passed; TESTING.md 5.6)."""
    shifts, dead = {}, []
    for stage, c in shift_counts.items():
        kinds = {}
        for name, (tried, ok) in (("reconnection", c[0:2]), ("replay", c[2:4])):
            kinds[name] = {"tried": int(tried), "succeeded": int(ok), "success_rate": float(ok / tried) if tried else None}
        shifts[stage] = kinds
        if c[0] + c[2] > 0 and c[1] + c[3] == 0:
            dead.append(stage)
    return shifts, dead


class ReSTIRPT(Integrator):
    name = "restir-pt"
    STAGES = ("gbuffer", "di.initial", "di.visibility", "di.temporal", "di.spatial", "di.shade", "trace_initial",
              "temporal", "spatial", "shade")
    KERNELS = (primary_hits_kernel, initial_kernel, temporal_kernel, spatial_kernel, shade_kernel)
    # The official defaults (ALGORITHMS.md 4.6), with the spatial radius scaled with the image; the
    # temporal cap of 20 was also the best of 1-50 and none by measurement (BENCHMARKS.md).
    SETTINGS = {"shift": "hybrid", "direct": "restir-di", "candidates": 1, "temporal": True, "temporal.cap": 20.0,
                "spatial.rounds": 1, "spatial.neighbors": 3, "spatial.radius": "auto", "rc.near_distance": 0.1,
                "rc.roughness": 0.2, "debug.mutation": "none", **DI_SETTINGS}
    SETTINGS_DOC = {
        "shift": "hybrid: replay to the first vertex that qualifies, then reconnect; reconnection: always at x2; "
                 "replay: the whole path",
        "direct": "restir-di: direct light at the primary hit from ReSTIR DI (the di.* settings); pt: ReSTIR PT "
                  "resamples every path",
        "candidates": "base paths per pixel (streaming RIS over their events; M = 1 per path)",
        "temporal": "temporal reuse of the previous frame's reservoirs (Talbot MIS)",
        "temporal.cap": "history confidence capped to this x the current one (<= 0: no cap, i.e. 1e6 x)",
        "spatial.rounds": "spatial reuse rounds (pairwise MIS)",
        "spatial.neighbors": "neighbours per round",
        "spatial.radius": "neighbour disk radius in pixels; auto: 20 px at 1080 lines scaled with the height, >= 2",
        "rc.near_distance": "hybrid: shortest reconnection segment, scene units",
        "rc.roughness": "hybrid: glossy lobes with a linear roughness above this are rough",
        "debug.mutation": "fault injection for the mutation tests (biased; the harness refuses it)",
        **DI_SETTINGS_DOC,
    }
    DESCRIPTION = "ReSTIR PT: path reuse with hybrid, reconnection or random-replay shifts; temporal and spatial reuse"
    SPATIAL_RADIUS_1080 = 20.0
    MUTATIONS = MUTATIONS

    @staticmethod
    def check_settings(settings: dict) -> None:
        from ...config import ConfigError

        if settings["shift"] not in SHIFTS:
            raise ConfigError(f"shift must be one of {', '.join(SHIFTS)}")
        if settings["direct"] not in ("restir-di", "pt"):
            raise ConfigError("direct must be restir-di or pt")
        if not 1 <= settings["candidates"] <= PT_MAX_CANDIDATES:
            raise ConfigError(f"candidates must be in [1, {PT_MAX_CANDIDATES}]")
        if not 0 <= settings["spatial.rounds"] <= MAX_SPATIAL_ROUNDS or \
                not 1 <= settings["spatial.neighbors"] <= PT_MAX_NEIGHBORS:
            raise ConfigError(f"spatial.rounds must be in [0, {MAX_SPATIAL_ROUNDS}] and spatial.neighbors in "
                              f"[1, {PT_MAX_NEIGHBORS}]")
        resolve_spatial_radius(settings["spatial.radius"], ReSTIRPT.SPATIAL_RADIUS_1080, 1)
        if not settings["rc.near_distance"] >= 0.0 or not settings["rc.roughness"] >= 0.0:
            raise ConfigError("rc.near_distance and rc.roughness must be >= 0")
        if settings["debug.mutation"] not in MUTATIONS:
            raise ConfigError(f"debug.mutation must be one of {', '.join(MUTATIONS)}")
        if settings["max_depth"] > PT_MAX_DEPTH:
            raise ConfigError(f"restir-pt renders max_depth up to {PT_MAX_DEPTH} (or -1)")
        check_di_settings(settings)

    def kernels(self) -> tuple:
        return (*self.KERNELS, *stage_kernels(self.settings["debug.mutation"]))

    def allocate(self) -> None:
        s = self.settings
        if s["max_depth"] < 0:
            s["max_depth"] = PT_MAX_DEPTH
            self.notes.append(f"restir-pt renders unbounded depth as max_depth {PT_MAX_DEPTH}")
        self.spatial_radius = resolve_spatial_radius(s["spatial.radius"], self.SPATIAL_RADIUS_1080, self.height)
        if s["spatial.radius"] == "auto":
            s["spatial.radius"] = self.spatial_radius
        self.gbuffers = PingPong(allocate_gbuffer(self, "gbuffer"), allocate_gbuffer(self, "gbuffer_prev"))
        self.primary_weight = self.buffer("primary_weight", float)
        self.emission = self.buffer("emission", wp.vec3)
        self.reservoirs = PingPong(self.buffer("reservoirs", PathReservoir),
                                   self.buffer("reservoirs_prev", PathReservoir))
        self.pass_out = self.buffer("reservoirs_pass", PathReservoir)
        self.sample_L = self.buffer("sample_L", wp.vec3)
        # per-pass scratch for the stats, like `events`: shift counts in reuse passes, origins in shading
        self.shift_events = self.buffer("shift_events", wp.vec4i)
        self.shift_counts: dict = {}   # per pass: [reconnections tried, succeeded, replays tried, succeeded]
        self.origins = np.zeros(3, np.int64)  # final samples by origin: canonical, temporal, spatial
        self.prev_camera = None
        # ReSTIR DI owns direct light at the primary hit (max_depth >= 2), on this method's G-buffers
        self.di = attach_direct_light(self)
        # the first vertex whose events ReSTIR PT resamples; paths need max_depth >= first + 2
        self.first_event = 1 if s["direct"] == "restir-di" else 0
        self.resamples = s["max_depth"] >= self.first_event + 2

    def params(self, frame: int, sample: int) -> PTRParams:
        s = self.settings
        p = PTRParams()
        p.seed = wp.uint32(s["seed"] & 0xFFFFFFFF)
        p.frame = wp.uint32(frame)
        p.sample = sample
        p.candidates = int(s["candidates"])
        p.max_depth = int(s["max_depth"])
        p.first_event = self.first_event
        p.shift = int(SHIFTS[s["shift"]])
        p.near_distance = float(s["rc.near_distance"])
        p.rough_threshold = float(s["rc.roughness"])
        p.temporal_cap = float(s["temporal.cap"])
        p.spatial_round = 0
        p.spatial_k = int(s["spatial.neighbors"])
        p.spatial_radius = float(self.spatial_radius)
        return p

    def reuse_pass(self, stage: str, kernel, inputs: list, in_place: bool = False) -> None:
        """The base class's ping-pong pass, with the pass's shift counts summed for the stats."""
        super().reuse_pass(stage, kernel, inputs, (self.shift_events,), in_place)
        acc = self.shift_counts.setdefault(stage, np.zeros(4, np.int64))
        acc += self.shift_events.numpy().sum(axis=0, dtype=np.int64)

    def render_frame(self, frame: int):
        sc = self.dscene.scene
        camera = self.camera(frame)
        mutation = self.settings["debug.mutation"]
        initial, temporal, spatial = stage_kernels(mutation)
        gb, res = self.gbuffers, self.reservoirs
        moments = PixelMoments((self.num_pixels, 3))
        for s in range(self.settings["spp"]):
            p = self.params(frame, s)
            self.run_stage("gbuffer", primary_hits_kernel, [sc, camera, p.seed, p.frame, s,
                                                            int(bool(self.settings["hide_emitters"]))],
                           [gb.current, self.primary_weight, self.emission])
            direct = self.emission
            if self.di is not None:
                self.di.resample_and_shade(frame, s)
                direct = self.di.sample_L
            if self.resamples:
                self.run_stage("trace_initial", initial, [sc, p, gb.current], [res.current])
                if self.settings["temporal"] and self.prev_camera is not None:
                    self.reuse_pass("temporal", temporal, [sc, p, self.prev_camera, gb.current, gb.previous,
                                                           res.previous])
                for rd in range(self.settings["spatial.rounds"]):
                    p.spatial_round = rd
                    self.reuse_pass("spatial", spatial, [sc, p, self.width, self.height, gb.current],
                                    mutation == "spatial_in_place")
                self.run_stage("shade", shade_kernel, [res.current, direct, self.primary_weight],
                               [self.sample_L, self.shift_events], nonfinite="nonfinite_outputs")
                L = self.sample_L.numpy()
                self.origins += self.shift_events.numpy().sum(axis=0, dtype=np.int64)[:3]
            else:
                L = direct.numpy()
            # this sample's final reservoirs and primary hits become the next one's history
            res.swap()
            if self.di is not None:
                self.di.end_sample(camera)
            gb.swap()
            self.prev_camera = camera
            moments.add(L)
            if self.on_samples is not None:
                self.on_samples(s + 1, self.settings["spp"])
        shape = (self.height, self.width, 3)
        return moments.mean.reshape(shape).astype(np.float32), moments.variance.reshape(shape)

    def stats(self) -> dict:
        """The base stats, ReSTIR DI's rays, and ReSTIR PT's reuse diagnostics (TESTING.md 5.12):
        per pass, the shifts tried and their success rate for reconnections (paths with an rc
        vertex) and pure replays; a pass whose shifts never succeed is listed as reuse dead. The
        fractions of the final samples (those with W > 0) taken from each kind of input."""
        out = super().stats()
        if self.di is not None:
            out["rays"] += self.di.rays
        shifts, dead = summarize_shifts(self.shift_counts)
        total = self.origins.sum()
        out["shifts"] = shifts
        out["reuse_dead"] = dead
        out["final_samples"] = {k: float(v / total) if total else 0.0
                                for k, v in zip(("canonical", "temporal", "spatial"), self.origins)}
        return out
