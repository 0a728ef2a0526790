"""ReSTIR DI as a pipeline of stages: G-buffer, initial RIS, visibility, temporal reuse,
spatial reuse rounds, shading.

render_frame is the table of contents; each stage is one kernel in its own file.
"""
import numpy as np
import warp as wp

from ...parallel import launch_pixels
from ..base import Integrator
from .events import COUNTER_NAMES, EV_RAYS
from .params import DIParams
from .reservoir import DIReservoir
from .s1_gbuffer import gbuffer_kernel
from .s2_initial import initial_kernel
from .s3_visibility import visibility_kernel
from .s4_temporal import temporal_kernel
from .s5_spatial import spatial_kernel
from .s6_shade import shade_kernel


class ReSTIRDI(Integrator):
    name = "restir-di"
    STAGES = ("gbuffer", "initial", "visibility", "temporal", "spatial", "shade")
    KERNELS = (gbuffer_kernel, initial_kernel, visibility_kernel, temporal_kernel, spatial_kernel, shade_kernel)
    # Literature defaults (see docs/restir_di.md): 32 light candidates; temporal reuse with the
    # history capped at 20x the current confidence; spatial reuse with 3 neighbours in a 30 px
    # radius, 2 rounds (Bitterli et al. 2020, unbiased variant).
    SETTINGS = {"candidates": 32, "candidates.bsdf": 1, "visibility": "reuse", "temporal": True, "temporal.cap": 20.0, "spatial.rounds": 2,
                "spatial.neighbors": 3, "spatial.radius": 30.0, "debug.mutation": "none"}
    VISIBILITY = ("reuse", "shading")
    MUTATIONS = ("none", "drop_empty_neighbors", "skip_zero_canonical", "spatial_in_place", "temporal_overweight",
                 "bsdf_unshadowed_reuse")
    FIXED_MAX_DEPTH = 2  # direct illumination: emission plus one bounce, Mitsuba's meaning

    @staticmethod
    def check_settings(settings: dict) -> None:
        from ...config import ConfigError

        if settings["candidates"] < 0 or settings["candidates.bsdf"] < 0 or \
                settings["candidates"] + settings["candidates.bsdf"] < 1:
            raise ConfigError("candidates and candidates.bsdf must be >= 0, with at least one candidate")
        if settings["visibility"] not in ReSTIRDI.VISIBILITY:
            raise ConfigError(f"visibility must be one of {', '.join(ReSTIRDI.VISIBILITY)}")
        reuse = settings["temporal"] or settings["spatial.rounds"] > 0
        if settings["candidates.bsdf"] > 0 and settings["visibility"] == "shading" and reuse and \
                settings["debug.mutation"] != "bsdf_unshadowed_reuse":
            # p_B omits V, so W is valid only for visibility-aware targets once samples are reused
            raise ConfigError("candidates.bsdf > 0 with reuse needs visibility=reuse "
                              "(unshadowed reuse of BSDF candidates is biased; see docs/restir_di.md)")
        if not 0 <= settings["spatial.rounds"] <= 8 or not 1 <= settings["spatial.neighbors"] <= 32:
            raise ConfigError("spatial.rounds must be in [0, 8] and spatial.neighbors in [1, 32]")
        if settings["spatial.radius"] <= 0:
            raise ConfigError("spatial.radius must be positive")
        if settings["debug.mutation"] not in ReSTIRDI.MUTATIONS:
            raise ConfigError(f"debug.mutation must be one of {', '.join(ReSTIRDI.MUTATIONS)}")

    def allocate(self) -> None:
        self.gb_tri = self.buffer("gb_tri", wp.int32)
        self.gb_bary = self.buffer("gb_bary", wp.vec2)
        self.gb_t = self.buffer("gb_t", float)
        self.gb_dir = self.buffer("gb_dir", wp.vec3)
        # previous sample's G-buffer, camera and final reservoirs (temporal inputs)
        self.prev_tri = self.buffer("prev_tri", wp.int32)
        self.prev_bary = self.buffer("prev_bary", wp.vec2)
        self.prev_t = self.buffer("prev_t", float)
        self.prev_dir = self.buffer("prev_dir", wp.vec3)
        self.prev_reservoirs = self.buffer("prev_reservoirs", DIReservoir)
        self.prev_camera = None
        self.gb_weight = self.buffer("gb_weight", float)
        self.emission = self.buffer("emission", wp.vec3)
        self.reservoirs = self.buffer("reservoirs", DIReservoir)
        self.reservoirs_back = self.buffer("reservoirs_back", DIReservoir)
        self.sample_L = self.buffer("sample_L", wp.vec3)
        self.events = self.buffer("events", wp.vec4i)  # per-stage scratch, summed into counters

    def params(self, frame: int, sample: int) -> DIParams:
        p = DIParams()
        p.seed = wp.uint32(self.settings["seed"] & 0xFFFFFFFF)
        p.frame = wp.uint32(frame)
        p.sample = sample
        p.candidates = int(self.settings["candidates"])
        p.bsdf_candidates = int(self.settings["candidates.bsdf"])
        p.visibility = int(self.settings["visibility"] == "reuse")
        p.hide_emitters = int(bool(self.settings["hide_emitters"]))
        p.temporal_cap = float(self.settings["temporal.cap"])
        p.spatial_round = 0
        p.spatial_k = int(self.settings["spatial.neighbors"])
        p.spatial_radius = float(self.settings["spatial.radius"])
        mutation = self.settings["debug.mutation"]
        p.mut_drop_empty = int(mutation == "drop_empty_neighbors")
        p.mut_skip_zero_canonical = int(mutation == "skip_zero_canonical")
        p.mut_temporal_overweight = int(mutation == "temporal_overweight")
        return p

    def launch(self, stage: str, kernel, inputs: list, outputs: list) -> None:
        """Run one stage; every stage writes `events` last, which is summed into the counters."""
        with self.timer.stage(stage):
            launch_pixels(kernel, self.num_pixels, inputs, [*outputs, self.events], self.device, self.slices,
                          self.reverse_launch)
        ev = self.events.numpy().sum(axis=0, dtype=np.int64)
        names = ("nonfinite_outputs" if stage == "shade" else "nonfinite_weights",) + COUNTER_NAMES[1:]
        for i, name in enumerate(names):
            self.counters[name] = self.counters.get(name, 0) + int(ev[i])
        self.rays += int(ev[EV_RAYS])

    def render_frame(self, frame: int):
        sc = self.dscene.scene
        camera = self.camera(frame)
        n, mean, m2 = 0, None, None
        for s in range(self.settings["spp"]):
            p = self.params(frame, s)
            gb = [self.gb_tri, self.gb_bary, self.gb_t, self.gb_dir]
            prev_gb = [self.prev_tri, self.prev_bary, self.prev_t, self.prev_dir]
            self.launch("gbuffer", gbuffer_kernel, [sc, camera, p], [*gb, self.gb_weight, self.emission])
            self.launch("initial", initial_kernel, [sc, p, *gb], [self.reservoirs])
            if p.visibility:
                self.launch("visibility", visibility_kernel, [sc, p, *gb, self.reservoirs], [self.reservoirs_back])
                self.reservoirs, self.reservoirs_back = self.reservoirs_back, self.reservoirs
            if self.settings["temporal"] and self.prev_camera is not None:
                self.launch("temporal", temporal_kernel,
                            [sc, p, self.prev_camera, *gb, *prev_gb, self.reservoirs, self.prev_reservoirs],
                            [self.reservoirs_back])
                self.reservoirs, self.reservoirs_back = self.reservoirs_back, self.reservoirs
            for rd in range(self.settings["spatial.rounds"]):
                p.spatial_round = rd
                if self.settings["debug.mutation"] == "spatial_in_place":  # race, for the R2 test only
                    self.launch("spatial", spatial_kernel, [sc, p, self.width, self.height, *gb, self.reservoirs],
                                [self.reservoirs])
                    continue
                self.launch("spatial", spatial_kernel, [sc, p, self.width, self.height, *gb, self.reservoirs],
                            [self.reservoirs_back])
                self.reservoirs, self.reservoirs_back = self.reservoirs_back, self.reservoirs  # ping-pong
            self.launch("shade", shade_kernel, [sc, p, *gb, self.gb_weight, self.emission, self.reservoirs],
                        [self.sample_L])
            # this sample's final reservoirs and G-buffer become the next one's history (swap)
            self.reservoirs, self.prev_reservoirs = self.prev_reservoirs, self.reservoirs
            self.gb_tri, self.prev_tri = self.prev_tri, self.gb_tri
            self.gb_bary, self.prev_bary = self.prev_bary, self.gb_bary
            self.gb_t, self.prev_t = self.prev_t, self.gb_t
            self.gb_dir, self.prev_dir = self.prev_dir, self.gb_dir
            self.prev_camera = camera
            L = self.sample_L.numpy().astype(np.float64)
            n += 1
            if mean is None:
                mean, m2 = L.copy(), np.zeros_like(L)
            else:
                delta = L - mean
                mean += delta / n
                m2 += delta * (L - mean)
        shape = (self.height, self.width, 3)
        return mean.reshape(shape).astype(np.float32), (m2 / n).reshape(shape)
