"""ReSTIR PT as a pipeline of stages: primary hits, ReSTIR DI (direct light at the primary hit,
unless direct=pt), trace and initial RIS, temporal reuse, MCMC suffix mutations (mcmc.steps > 0),
spatial reuse rounds, shading.

render_sample is the table of contents; each stage is one kernel in its own file.
"""
import dataclasses
import functools

import numpy as np
import warp as wp

from ...device.streams import PT_MAX_MCMC_STEPS, PT_MAX_NEIGHBORS
from ...settings import EMISSION_RAYS_DOC, MUTATION_DOC, setting
from ..common.gbuffer import LENS_MUTATION
from ..common.mutations import Mutations
from ..common.primary_hits import primary_hits_kernel
from ..common.spatial_settings import SpatialReuseSettings, spatial_reuse
from ..path_reuse.direct_light import DISettings, di_component
from ..path_reuse.integrator import PathReuseIntegrator, PathReuseSettings
from ..path_reuse.params import PathReuseParams
from ..path_reuse.shift import MUTATIONS as SHIFT_MUTATIONS
from ..path_reuse.shift import make_shift
from .s1_initial import initial_kernel
from .s2_temporal import make_trace_temporal_kernel, temporal_kernel, trace_temporal_kernel
from .s3_mcmc import MUTATIONS as MCMC_MUTATIONS
from .s3_mcmc import make_mcmc_kernel, mcmc_kernel
from .s4_spatial import (make_reciprocal_spatial_kernel, make_spatial_kernel, pairings_kernel,
                         reciprocal_spatial_kernel, spatial_kernel)
from .s5_shade import shade_kernel


def _shift_mutant(mutation: str) -> tuple:
    shift, module = make_shift(mutation, inline=True), f"restir_pt_{mutation}"
    return (make_trace_temporal_kernel(shift, module=module), mcmc_kernel, make_spatial_kernel(shift, module=module),
            make_reciprocal_spatial_kernel(shift, module=module))


def _mcmc_mutant(mutation: str) -> tuple:
    return (trace_temporal_kernel, make_mcmc_kernel(mutation, f"restir_pt_mcmc_{mutation}"), spatial_kernel,
            reciprocal_spatial_kernel)


# Fault injections for the mutation tests (common/mutations.py), each a build of the shipped
# (trace + temporal, mcmc, spatial, reciprocal spatial) kernels or, for the race, of the pipeline.
# They are built for the fused pipeline, the one that ships; stages.split refuses them (check_settings).
MUTATIONS = Mutations((trace_temporal_kernel, mcmc_kernel, spatial_kernel, reciprocal_spatial_kernel), {
    **{m: functools.partial(_shift_mutant, m) for m in SHIFT_MUTATIONS},
    **{f"mcmc_{m}": functools.partial(_mcmc_mutant, m) for m in MCMC_MUTATIONS},
    "m_per_event": lambda: (make_trace_temporal_kernel(m_per_event=True, module="restir_pt_m_per_event"),
                            mcmc_kernel, spatial_kernel, reciprocal_spatial_kernel),
    "drop_failed_shifts": lambda: (
        make_trace_temporal_kernel(drop_failed=True, module="restir_pt_drop_failed_shifts"), mcmc_kernel,
        make_spatial_kernel(drop_failed=True, module="restir_pt_drop_failed_shifts"),
        make_reciprocal_spatial_kernel(drop_failed=True, module="restir_pt_drop_failed_shifts")),
    "spatial_in_place": None,  # the spatial pass writes its own input (race, R2)
    # a thin lens's primary rays rebuilt from the lens's centre (common/gbuffer.py)
    LENS_MUTATION: None,
    # direct=nee whose trace stage also resamples the events at x_0 it sums (first_event 0):
    # direct light counted twice
    "nee_also_resampled": None,
    # emission.rays: the extra camera rays at the lattice's points unshifted by the sample's
    # position (common/primary_hits.py builds that stage's kernel with the defect)
    "emission_lattice_fixed": None,
    # emission.adaptive: the n rays where the sample's own ray saw emission, not where the previous
    # launch saw it vary (the same module builds it)
    "emission_rays_by_own_ray": None,
    # shade.expected: the reciprocal spatial pass's expected output not divided by V + 1
    "expected_unnormalized": lambda: (
        trace_temporal_kernel, mcmc_kernel, spatial_kernel,
        make_reciprocal_spatial_kernel(expected_unnormalized=True, module="restir_pt_expected_unnormalized")),
})


# The official defaults (docs/theory/restir_pt.md#defaults-the-official-implementation-and-this-project),
# with the spatial radius in pixels (scaled up above
# 1080 lines), but for two chosen by the denoised equal-time measurement
# (docs/changelog.md#restir-pt-directpt-temporalcap5): direct light in the path reservoirs (direct=pt: 17-35% cheaper a
# frame, 252 B per pixel) and a temporal cap of 5, not the official 20 (less correlated error);
# together the lowest error after the denoiser at equal time in 5 of 8 runs and the lowest
# accumulated error in all 8. The official values are direct=restir-di, temporal.cap=20. And
# reciprocal neighbours (spatial.reciprocal, ReSTIR PT Enhanced's; docs/changelog.md#restir-pt-reciprocal-neighbours):
# half the spatial shifts, frames 7-14% cheaper at 128 lines and 15-19% at 512, less
# denoised error in 5 of 8 runs (geometric mean 3.54x the path tracer's against 3.77x), less
# correlated in 7 of 8, lower accumulated error in all 8.
# And emission.rays 4 (every other method's default is 1): the emitter's edge seen directly,
# sampled by one ray a frame, was the largest error the denoiser left on the glossy Cornell box,
# and path reuse cannot lower it. With four rays the defaults went from 1.09x and 1.25x above the
# path tracer at equal time after the denoiser there to 1.21x and 1.16x below it, with the other
# scenes unchanged (no emitter in view); the frame 2-4% dearer at 128 lines, about a quarter of a
# path-tracer frame more at 512 with the rays at every pixel (the primary-hit stage 60 -> 200-230 ms;
# docs/changelog.md#emissionrays-4-for-restir-pt-8-for-suffix-restir).
@dataclasses.dataclass
class PTSettings(PathReuseSettings):
    emission_rays: int = setting("emission.rays", 4, EMISSION_RAYS_DOC)
    direct: str = setting("direct", "pt", "pt: the method's paths own every event, direct light included; "
                          "restir-di: direct light at the primary hit from ReSTIR DI (the di.* settings; the "
                          "official ReSTIR PT's choice); nee: the base paths' events at the primary hit summed as "
                          "the path tracer sums them, not resampled (+12 B per pixel)")
    temporal: bool = setting("temporal", True, "temporal reuse of the previous frame's reservoirs (Talbot MIS)")
    temporal_previous_scene: bool = setting("temporal.previous_scene", True, "an animated scene: the current "
                                            "sample replayed in the previous frame's scene for its density there "
                                            "(false: in the current one, biased where things moved; the validation "
                                            "harness refuses it)")
    temporal_cap: float = setting("temporal.cap", 5.0, "history confidence capped to this x the current one (<= 0: "
                                  "no cap, i.e. 1e6 x; the official value is 20)")
    shade_expected: bool = setting("shade.expected", False, "the image takes the last resampling pass's expected "
                                   "output given its inputs (each input's sample weighted by its chance of being "
                                   "selected) instead of the selected sample's: the same luminance, the inputs' "
                                   "colours averaged (Rao-Blackwell; unbiased, no extra rays, +12 B per pixel)")
    mcmc_start: str = setting("mcmc.start", "z", "where an MCMC mutation redraws the path: z (after the reconnection "
                              "vertex, which stays) or rc_prev (after the vertex before it: z moves too)")
    mcmc_steps: int = setting("mcmc.steps", 0, "MCMC mutations of each pixel's sample per frame, after temporal and "
                              "before spatial reuse: the path redrawn after mcmc.start, accepted with min(1, p_hat "
                              "ratio) (unbiased; measured not to decorrelate the error, docs/guide/decorrelation.md; 0: off)")
    spatial: SpatialReuseSettings = spatial_reuse("spatial.", radius_at_1080=20.0, reciprocal=True)
    rc_near_distance: float = setting("rc.near_distance", 0.1, "hybrid: shortest reconnection segment, scene units")
    rc_roughness: float = setting("rc.roughness", 0.2, "hybrid: glossy lobes with a linear roughness above this "
                                  "are rough")
    stages_split: bool = setting("stages.split", False, "trace + initial RIS and temporal reuse as two kernels, "
                                 "each timed (they run fused otherwise; the same images bit for bit), with a "
                                 "third path-reservoir buffer (+76 B per pixel)", static=True)
    debug_mutation: str = setting("debug.mutation", "none", MUTATION_DOC, static=True)  # builds mutant kernels
    di: DISettings = di_component()


class ReSTIRPT(PathReuseIntegrator):
    name = "restir-pt"
    STAGES = ("gbuffer", "di.initial_temporal", "di.initial", "di.visibility", "di.temporal", "di.spatial", "di.shade",
              "trace_temporal", "trace_initial", "temporal", "mcmc", "spatial", "shade")
    KERNELS = (primary_hits_kernel, trace_temporal_kernel, mcmc_kernel, spatial_kernel, reciprocal_spatial_kernel,
               shade_kernel)
    Settings = PTSettings
    DESCRIPTION = "ReSTIR PT: path reuse with hybrid, reconnection or random-replay shifts; temporal and spatial reuse"
    MUTATIONS = MUTATIONS

    RESERVOIRS = "reservoirs"

    @staticmethod
    def motion_refusal(settings) -> str | None:
        if not settings.temporal or settings.shift == "replay":
            return None
        return (f"restir-pt's temporal reuse with the {settings.shift} shift keeps a path's suffix after its "
                "reconnection vertex as cached radiance, which would have to be traced again in each frame's scene: "
                "--set shift=replay (traced whole in each frame's scene), or --set temporal=false")

    @staticmethod
    def check_settings(settings: PTSettings) -> None:
        from ...config import ConfigError

        ReSTIRPT.check_path_settings(settings)
        if not 0 <= settings.mcmc_steps <= PT_MAX_MCMC_STEPS:
            raise ConfigError(f"mcmc.steps must be in [0, {PT_MAX_MCMC_STEPS}]")
        if settings.mcmc_start not in ("z", "rc_prev"):
            raise ConfigError("mcmc.start must be z or rc_prev")
        if settings.shade_expected and settings.mcmc_steps > 0 and settings.spatial.rounds == 0:
            raise ConfigError("shade.expected needs a resampling pass last: with mcmc.steps > 0, spatial.rounds >= 1")
        if settings.stages_split and MUTATIONS.builds_kernels(settings.debug_mutation):
            raise ConfigError("debug.mutation builds the fused pipeline's kernels; it cannot run with stages.split")

    def kernels(self) -> tuple:
        split = (initial_kernel, temporal_kernel) if self.settings.stages_split else ()
        return (*self.KERNELS, *split, *MUTATIONS.kernels(self.settings.debug_mutation))

    def wants_pass_buffer(self) -> bool:
        """Only the split temporal kernel needs a third path-reservoir buffer: it reads the history
        and the new reservoirs and writes neither. Fused, every pass after it writes into the
        history's buffer (path_reuse/integrator.py)."""
        return bool(self.settings.stages_split)

    DIRECT = ("restir-di", "pt", "nee")

    def allocate(self) -> None:
        self.allocate_path_reuse()
        # direct=nee: the trace stage's direct light (emission seen directly and x_0's summed
        # events); otherwise never written, one element
        nee = self.settings.direct == "nee"
        self.direct_nee = self.buffer("direct_nee", wp.vec3) if nee else wp.zeros(1, dtype=wp.vec3, device=self.device)
        # shade.expected: the last pass's expected output (and the reciprocal pass's running sum)
        ex = self.settings.shade_expected
        self.expected = self.buffer("expected", wp.vec3) if ex else wp.zeros(1, dtype=wp.vec3, device=self.device)
        # a round's pairings for spatial.reciprocal (16 B per neighbour, not per pixel)
        self.pairings = wp.zeros(PT_MAX_NEIGHBORS, dtype=wp.vec4i, device=self.device)
        self.origins = np.zeros(3, np.int64)  # final samples by origin: canonical, temporal, spatial
        self.mcmc_counts = np.zeros(3, np.int64)  # samples with a suffix, valid proposals, accepted

    def params(self, frame: int, sample: int) -> PathReuseParams:
        s = self.settings
        p = self.pt_params(frame, sample, s.rc_near_distance, s.temporal_cap)
        if s.debug_mutation == "nee_also_resampled":
            p.first_event = 0
        return p

    def resample_sample(self, frame: int, sample: int, direct):
        sc = self.dscene.scene
        mutation = self.settings.debug_mutation
        trace_temporal, mcmc, spatial, reciprocal = MUTATIONS.kernels(mutation)
        gb, res = self.gbuffers, self.reservoirs
        p = self.params(frame, sample)
        temporal = bool(self.settings.temporal and self.prev_camera is not None)
        sp = self.settings.spatial
        # shade.expected: the last resampling pass writes its expected output (the fused trace +
        # temporal kernel even without a history: the new reservoir's own F W)
        expected = bool(self.settings.shade_expected)
        p.expected_out = int(expected and sp.rounds == 0)
        use_expected = expected and (sp.rounds > 0 or not self.settings.stages_split or temporal)
        if self.settings.stages_split:
            self.run_stage("trace_initial", initial_kernel, [sc, p, gb.current, self.emission, self.primary_weight],
                           [res.current, self.direct_nee])
            if temporal:
                self.reuse_pass("temporal", temporal_kernel,
                                [sc, self.history_scene(), p, self.current_camera, self.prev_camera, gb.current,
                                 gb.previous, res.previous], scratch=(self.expected,))
        else:
            prev_camera = self.prev_camera or self.dscene.camera  # unread without temporal reuse
            self.run_stage("trace_temporal", trace_temporal,
                           [sc, self.history_scene(), p, int(temporal), self.current_camera, prev_camera, gb.current,
                            gb.previous, res.previous, self.emission, self.primary_weight],
                           [res.current, self.direct_nee, self.expected, self.shift_events])
            if temporal:
                self.count_shifts("temporal")
        if self.settings.mcmc_steps > 0:
            self.reuse_pass("mcmc", mcmc, [sc, p, int(self.settings.mcmc_steps),
                                           int(self.settings.mcmc_start == "rc_prev"), gb.current], counts=("mcmc",))
        for rd in range(sp.rounds):
            p.spatial_round = rd
            p.expected_out = int(expected and rd == sp.rounds - 1)
            if sp.reciprocal:  # one launch per neighbour, the pass's state between them in sample_L (and expected)
                wp.launch(pairings_kernel, dim=sp.neighbors, inputs=[p], outputs=[self.pairings], device=self.device)
                self.reuse_pass("spatial", reciprocal, [sc, p, self.width, self.height, gb.current, self.pairings],
                                mutation == "spatial_in_place", parts=sp.neighbors,
                                scratch=(self.sample_L, self.expected))
            else:
                self.reuse_pass("spatial", spatial, [sc, p, self.width, self.height, gb.current],
                                mutation == "spatial_in_place", scratch=(self.expected,))
        if self.settings.direct == "nee":  # the trace stage's: the emission seen directly and x_0's events
            direct = self.direct_nee
        self.run_stage("shade", shade_kernel, [res.current, direct, self.primary_weight, self.expected,
                                               int(use_expected)],
                       [self.sample_L, self.shift_events], nonfinite="nonfinite_outputs")
        self.tally.add(("origins",), self.shift_events)  # the shade stage counts the final samples' origins
        return self.sample_L

    def take_tally(self, key, sums: np.ndarray) -> None:
        if key[0] == "origins":
            self.origins += sums[:3]
        elif key[0] == "mcmc":
            self.mcmc_counts += sums[:3]
        else:
            super().take_tally(key, sums)

    def stats(self) -> dict:
        """The path-reuse stats, and the fractions of the final samples (those with W > 0) taken
        from each kind of input: the pixel's own base path, temporal and spatial reuse."""
        out = super().stats()
        total = self.origins.sum()
        out["final_samples"] = {k: float(v / total) if total else 0.0
                                for k, v in zip(("canonical", "temporal", "spatial"), self.origins)}
        if self.settings.mcmc_steps > 0:
            samples, valid, accepted = (int(v) for v in self.mcmc_counts)
            proposals = samples * int(self.settings.mcmc_steps)
            out["mcmc"] = {"samples": samples, "proposals": proposals, "valid_proposals": valid, "accepted": accepted,
                           "acceptance_rate": accepted / proposals if proposals else None}
        return out
