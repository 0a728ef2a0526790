"""ReSTIR PT as a pipeline of stages: primary hits, ReSTIR DI (direct light at the primary hit,
unless direct=pt), trace and initial RIS, temporal reuse, spatial reuse rounds, shading.

render_sample is the table of contents; each stage is one kernel in its own file.
"""
import dataclasses
import functools

import numpy as np

from ...settings import MUTATION_DOC, setting
from ..common.mutations import Mutations
from ..common.primary_hits import primary_hits_kernel
from ..common.spatial_settings import SpatialReuseSettings, spatial_reuse
from ..path_reuse.direct_light import DISettings, di_component
from ..path_reuse.integrator import PathReuseIntegrator, PathReuseSettings
from ..path_reuse.params import PathReuseParams
from ..path_reuse.shift import MUTATIONS as SHIFT_MUTATIONS
from ..path_reuse.shift import make_shift
from .s1_initial import initial_kernel, make_initial_kernel
from .s2_temporal import make_temporal_kernel, temporal_kernel
from .s3_spatial import make_spatial_kernel, spatial_kernel
from .s4_shade import shade_kernel


def _shift_mutant(mutation: str) -> tuple:
    shift, module = make_shift(mutation), f"restir_pt_{mutation}"
    return initial_kernel, make_temporal_kernel(shift, module=module), make_spatial_kernel(shift, module=module)


# Fault injections for the mutation tests (common/mutations.py), each a build of the (initial,
# temporal, spatial) kernels or, for the race, of the pipeline.
MUTATIONS = Mutations((initial_kernel, temporal_kernel, spatial_kernel), {
    **{m: functools.partial(_shift_mutant, m) for m in SHIFT_MUTATIONS},
    "m_per_event": lambda: (make_initial_kernel(m_per_event=True), temporal_kernel, spatial_kernel),
    "drop_failed_shifts": lambda: (initial_kernel,
                                   make_temporal_kernel(drop_failed=True, module="restir_pt_drop_failed_shifts"),
                                   make_spatial_kernel(drop_failed=True, module="restir_pt_drop_failed_shifts")),
    "spatial_in_place": None,  # the spatial pass writes its own input (race, R2)
})


# The official defaults (ALGORITHMS.md 4.6), with the spatial radius scaled with the image; the
# temporal cap of 20 was also the best of 1-50 and none by measurement (BENCHMARKS.md).
@dataclasses.dataclass
class PTSettings(PathReuseSettings):
    temporal: bool = setting("temporal", True, "temporal reuse of the previous frame's reservoirs (Talbot MIS)")
    temporal_cap: float = setting("temporal.cap", 20.0, "history confidence capped to this x the current one (<= 0: "
                                  "no cap, i.e. 1e6 x)")
    spatial: SpatialReuseSettings = spatial_reuse("spatial.", radius_at_1080=20.0)
    rc_near_distance: float = setting("rc.near_distance", 0.1, "hybrid: shortest reconnection segment, scene units")
    rc_roughness: float = setting("rc.roughness", 0.2, "hybrid: glossy lobes with a linear roughness above this "
                                  "are rough")
    debug_mutation: str = setting("debug.mutation", "none", MUTATION_DOC, static=True)  # builds mutant kernels
    di: DISettings = di_component()


class ReSTIRPT(PathReuseIntegrator):
    name = "restir-pt"
    STAGES = ("gbuffer", "di.initial", "di.visibility", "di.temporal", "di.spatial", "di.shade", "trace_initial",
              "temporal", "spatial", "shade")
    KERNELS = (primary_hits_kernel, initial_kernel, temporal_kernel, spatial_kernel, shade_kernel)
    Settings = PTSettings
    DESCRIPTION = "ReSTIR PT: path reuse with hybrid, reconnection or random-replay shifts; temporal and spatial reuse"
    MUTATIONS = MUTATIONS

    RESERVOIRS = "reservoirs"

    @staticmethod
    def check_settings(settings: PTSettings) -> None:
        ReSTIRPT.check_path_settings(settings)

    def kernels(self) -> tuple:
        return (*self.KERNELS, *MUTATIONS.kernels(self.settings.debug_mutation))

    def allocate(self) -> None:
        self.allocate_path_reuse()
        self.origins = np.zeros(3, np.int64)  # final samples by origin: canonical, temporal, spatial

    def params(self, frame: int, sample: int) -> PathReuseParams:
        s = self.settings
        return self.pt_params(frame, sample, s.rc_near_distance, s.temporal_cap)

    def resample_sample(self, frame: int, sample: int, direct):
        sc = self.dscene.scene
        mutation = self.settings.debug_mutation
        initial, temporal, spatial = MUTATIONS.kernels(mutation)
        gb, res = self.gbuffers, self.reservoirs
        p = self.params(frame, sample)
        self.run_stage("trace_initial", initial, [sc, p, gb.current], [res.current])
        if self.settings.temporal and self.prev_camera is not None:
            self.reuse_pass("temporal", temporal, [sc, p, self.prev_camera, gb.current, gb.previous, res.previous])
        for rd in range(self.settings.spatial.rounds):
            p.spatial_round = rd
            self.reuse_pass("spatial", spatial, [sc, p, self.width, self.height, gb.current],
                            mutation == "spatial_in_place")
        self.run_stage("shade", shade_kernel, [res.current, direct, self.primary_weight],
                       [self.sample_L, self.shift_events], nonfinite="nonfinite_outputs")
        self.tally.add(("origins",), self.shift_events)  # the shade stage counts the final samples' origins
        return self.sample_L

    def take_tally(self, key, sums: np.ndarray) -> None:
        if key[0] == "origins":
            self.origins += sums[:3]
        else:
            super().take_tally(key, sums)

    def stats(self) -> dict:
        """The path-reuse stats, and the fractions of the final samples (those with W > 0) taken
        from each kind of input: the pixel's own base path, temporal and spatial reuse."""
        out = super().stats()
        total = self.origins.sum()
        out["final_samples"] = {k: float(v / total) if total else 0.0
                                for k, v in zip(("canonical", "temporal", "spatial"), self.origins)}
        return out
