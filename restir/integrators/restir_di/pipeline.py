"""ReSTIR DI as a pipeline of stages: primary hits, initial RIS, visibility, temporal reuse,
spatial reuse rounds, shading.

render_sample is the table of contents; each stage is one kernel in its own file.
"""
import dataclasses

import warp as wp

from ...device.streams import DI_MAX_CANDIDATES, DI_MAX_NEIGHBORS
from ...settings import MUTATION_DOC, Settings, setting
from ..base import Integrator
from ..common.gbuffer import LENS_MUTATION, PingPong, allocate_primary_gbuffer
from ..common.mutations import Mutations
from ..common.primary_hits import primary_hits_kernel, trace_primary_hits
from ..common.spatial_settings import SpatialReuseSettings, spatial_reuse
from .params import DIParams
from .reservoir import DIReservoir
from .s1_initial import initial_kernel
from .s2_visibility import visibility_kernel
from .s3_temporal import initial_temporal_kernel, make_initial_temporal_kernel, temporal_kernel
from .s4_spatial import make_spatial_kernel, spatial_kernel
from .s5_shade import shade_kernel

# Fault injections for the mutation tests (common/mutations.py), each a build of the (initial +
# visibility + temporal, spatial) kernels or, for the race and the check, of the pipeline. They are
# built for the fused pipeline, the one that ships; stages.split refuses them (check_settings).
MUTATIONS = Mutations((initial_temporal_kernel, spatial_kernel), {
    "drop_empty_neighbors": lambda: (initial_temporal_kernel, make_spatial_kernel(drop_empty_neighbors=True)),  # A3
    "skip_zero_canonical": lambda: (make_initial_temporal_kernel("skip_zero_canonical"),                    # A1
                                    make_spatial_kernel(skip_zero_canonical=True)),
    "temporal_overweight": lambda: (make_initial_temporal_kernel("overweight_history"), spatial_kernel),  # feedback
    # under scene motion: the history's domain evaluated in the current scene; the previous frame's
    # lights replaced by the current ones (a host-side choice of the previous scene:
    # DeviceScene.with_current_lights)
    "current_scene_history": lambda: (make_initial_temporal_kernel("current_scene_history"), spatial_kernel),
    "previous_lights_dropped": None,
    "spatial_in_place": None,        # the spatial pass writes its own input (race, R2)
    "bsdf_unshadowed_reuse": None,   # lets check_settings accept a biased combination
    # a thin lens's primary rays rebuilt from the lens's centre (common/gbuffer.py)
    LENS_MUTATION: None,
})


# Defaults chosen by ReSTIR DI's own measurement (docs/changelog.md#restir-di-temporalcap2-spatialrounds1-5-px;
# benchmarks/bench_di_defaults.py, phases rules, candidates and rules_timing): 32 light candidates;
# temporal reuse with the history capped at 2x the current confidence; one spatial round of 3
# neighbours in a disk of 5 px up to 1080 lines, scaled with the image height above. On the
# many-light room and the Cornell box (emitters hidden) at 64, 128 and 256 lines, two seeds, reuse
# lowers the per-frame error more with these than with cap 5, 2 rounds and 15 px (many lights at
# 128 lines: 2.04x against no reuse, was 1.72x), as much or more after Open Image Denoise (there
# 1.11x either way), at 0.82-0.90x the frame time (medians of alternating runs). Smaller disks
# lower the raw error further
# (2 px: 2.27x) but put the copies spatial reuse makes side by side, which the denoiser keeps:
# after it, 2 px gave 0.63x, worse than no reuse. ReSTIR PT's and Suffix ReSTIR's ReSTIR DI
# component keeps its own defaults (path_reuse/direct_light.py).
@dataclasses.dataclass
class DISettings(Settings):
    candidates: int = setting("candidates", 32, "light-sampled candidates N_L of the initial RIS")
    candidates_bsdf: int = setting("candidates.bsdf", 1, "BSDF-sampled candidates N_B (with reuse: needs "
                                   "visibility=reuse)")
    visibility: str = setting("visibility", "reuse", "reuse: visibility-aware targets (a visibility stage); "
                              "shading: V traced at shading only")
    temporal: bool = setting("temporal", True, "temporal reuse of the previous frame's reservoirs")
    temporal_cap: float = setting("temporal.cap", 2.0, "history confidence capped to this x the current one "
                                  "(<= 0: no cap, i.e. 1e6 x)")
    temporal_previous_scene: bool = setting("temporal.previous_scene", True, "an animated scene: the history's "
                                            "targets and motion vectors in the previous frame's scene (false: in "
                                            "the current one, cheaper and biased where things moved; the "
                                            "validation harness refuses it)")
    spatial: SpatialReuseSettings = spatial_reuse("spatial.", radius_at_1080=5.0, rounds=1)
    stages_split: bool = setting("stages.split", False, "initial RIS, visibility and temporal reuse as three "
                                 "kernels, each timed (they run fused otherwise; the same images bit for bit), "
                                 "with a third reservoir buffer (+24 B per pixel)", static=True)
    debug_mutation: str = setting("debug.mutation", "none", MUTATION_DOC, static=True)  # builds mutant kernels


class ReSTIRDI(Integrator):
    name = "restir-di"
    STAGES = ("gbuffer", "initial_temporal", "initial", "visibility", "temporal", "spatial", "shade")
    KERNELS = (primary_hits_kernel, initial_temporal_kernel, spatial_kernel, shade_kernel)
    Settings = DISettings
    DESCRIPTION = "ReSTIR DI (direct light, max_depth 2): initial RIS, visibility, temporal and spatial reuse"
    VISIBILITY = ("reuse", "shading")
    MUTATIONS = MUTATIONS
    FIXED_MAX_DEPTH = 2  # direct illumination: emission plus one bounce, Mitsuba's meaning

    def __init__(self, *args, primary=None, **kw):
        """primary: (G-buffer ping-pong, filter weights, emission) of the method this one is a part
        of (ReSTIR PT's direct light), which then owns and fills them; None: its own."""
        self.primary = primary
        super().__init__(*args, **kw)

    @staticmethod
    def check_settings(settings: DISettings) -> None:
        from ...config import ConfigError

        if settings.candidates < 0 or settings.candidates_bsdf < 0 or \
                not 1 <= settings.candidates + settings.candidates_bsdf <= DI_MAX_CANDIDATES:
            raise ConfigError("candidates and candidates.bsdf must be >= 0, with at least one candidate "
                              f"and at most {DI_MAX_CANDIDATES} together")
        if settings.visibility not in ReSTIRDI.VISIBILITY:
            raise ConfigError(f"visibility must be one of {', '.join(ReSTIRDI.VISIBILITY)}")
        reuse = settings.temporal or settings.spatial.rounds > 0
        if settings.candidates_bsdf > 0 and settings.visibility == "shading" and reuse and \
                settings.debug_mutation != "bsdf_unshadowed_reuse":
            # p_B omits V, so W is valid only for visibility-aware targets once samples are reused
            raise ConfigError("candidates.bsdf > 0 with reuse needs visibility=reuse "
                              "(unshadowed reuse of BSDF candidates is biased; see docs/guide/restir_di.md)")
        settings.spatial.check(DI_MAX_NEIGHBORS)
        if settings.debug_mutation not in ReSTIRDI.MUTATIONS:
            raise ConfigError(f"debug.mutation must be one of {', '.join(ReSTIRDI.MUTATIONS)}")
        if settings.stages_split and MUTATIONS.builds_kernels(settings.debug_mutation):
            raise ConfigError("debug.mutation builds the fused pipeline's kernels; it cannot run with stages.split")

    def kernels(self) -> tuple:
        split = (initial_kernel, visibility_kernel, temporal_kernel) if self.settings.stages_split else ()
        return (*self.KERNELS, *split, *MUTATIONS.kernels(self.settings.debug_mutation))

    def allocate(self) -> None:
        self.spatial_radius = self.settings.spatial.resolve_radius(self.height)
        if self.primary is None:
            # this sample's primary hits and the previous sample's (the temporal technique's domain)
            self.gbuffers = PingPong(allocate_primary_gbuffer(self, "gbuffer"),
                                     allocate_primary_gbuffer(self, "gbuffer_prev"))
            self.primary_weight = self.buffer("primary_weight", float)
            self.emission = self.buffer("emission", wp.vec3)
        else:  # a component of another method, which owns the primary-hit layer
            self.gbuffers, self.primary_weight, self.emission = self.primary
        # this sample's reservoirs as the passes refine them, and the previous sample's final ones
        self.reservoirs = PingPong(self.buffer("reservoirs", DIReservoir), self.buffer("reservoirs_prev", DIReservoir))
        # each reuse pass's output (ping-pong): only the split stages need a third buffer, since their
        # visibility and temporal passes run while the history is still to be read; fused, the
        # passes write into the history's buffer (Integrator.reuse_pass)
        self.pass_out = self.buffer("reservoirs_pass", DIReservoir) if self.settings.stages_split else None
        self.prev_camera = None
        self.prev_scene = None  # the scene of the previous sample (the history's domain)
        self.current_camera = self.dscene.camera  # the camera of the sample being rendered
        self.sample_L = self.buffer("sample_L", wp.vec3)

    def params(self, frame: int, sample: int) -> DIParams:
        p = DIParams()
        p.seed = wp.uint32(self.settings.seed & 0xFFFFFFFF)
        p.frame = wp.uint32(frame)
        p.sample = sample
        p.candidates = int(self.settings.candidates)
        p.bsdf_candidates = int(self.settings.candidates_bsdf)
        p.visibility = int(self.settings.visibility == "reuse")
        p.hide_emitters = int(bool(self.settings.hide_emitters))
        p.temporal_cap = float(self.settings.temporal_cap)
        p.spatial_round = 0
        p.spatial_k = int(self.settings.spatial.neighbors)
        p.spatial_radius = float(self.spatial_radius)
        return p

    def trace_primary(self, frame: int, sample: int, camera) -> None:
        """The primary-hit stage of one sample (skipped when another method owns that layer)."""
        p = self.params(frame, sample)
        trace_primary_hits(self, camera, p.seed, p.frame, sample, p.hide_emitters, self.gbuffers.current,
                           self.primary_weight, self.emission)

    def history_scene(self):
        """Integrator.history_scene; the mutation previous_lights_dropped: the previous scene with
        this one's lights."""
        sc = super().history_scene()
        if sc is self.prev_scene and self.settings.debug_mutation == "previous_lights_dropped":
            return self.dscene.with_current_lights(sc)
        return sc

    def resample_and_shade(self, frame: int, sample: int) -> None:
        """Every stage after the primary hits, for one sample: direct light into `sample_L`."""
        sc = self.dscene.scene
        prev_sc = self.history_scene()
        initial_temporal, spatial = MUTATIONS.kernels(self.settings.debug_mutation)
        in_place = self.settings.debug_mutation == "spatial_in_place"
        gb, res = self.gbuffers, self.reservoirs
        p = self.params(frame, sample)
        temporal = bool(self.settings.temporal and self.prev_camera is not None)
        if self.settings.stages_split:
            self.run_stage("initial", initial_kernel, [sc, p, gb.current], [res.current])
            if p.visibility:
                self.reuse_pass("visibility", visibility_kernel, [sc, p, gb.current])
            if temporal:
                self.reuse_pass("temporal", temporal_kernel,
                                [sc, prev_sc, p, self.current_camera, self.prev_camera, gb.current, gb.previous,
                                 res.previous])
        else:
            self.run_stage("initial_temporal", initial_temporal, [sc, prev_sc, p, int(temporal), self.current_camera,
                                                                  self.prev_camera or self.dscene.camera, gb.current,
                                                                  gb.previous, res.previous], [res.current])
        for rd in range(self.settings.spatial.rounds):
            p.spatial_round = rd
            self.reuse_pass("spatial", spatial, [sc, p, self.width, self.height, gb.current], in_place=in_place)
        self.run_stage("shade", shade_kernel, [sc, p, gb.current, self.primary_weight, self.emission,
                                               res.current], [self.sample_L], nonfinite="nonfinite_outputs")

    def end_sample(self, camera) -> None:
        """This sample's final reservoirs become the next one's history (the owner of the primary-hit
        layer swaps the G-buffers)."""
        self.reservoirs.swap()
        self.prev_camera = camera
        self.prev_scene = self.dscene.scene

    def render_sample(self, frame: int, sample: int, camera):
        self.current_camera = camera
        self.trace_primary(frame, sample, camera)
        self.resample_and_shade(frame, sample)
        self.end_sample(camera)
        self.gbuffers.swap()
        return self.sample_L
