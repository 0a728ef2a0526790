"""Reference path tracer: NEE and BSDF sampling combined with the balance heuristic.

Stage `path_trace` (one kernel): reads the scene and camera; writes `frame_mean` and
`frame_m2` (per-pixel mean and sum of squared deviations of this frame's spp samples, by
Welford's update: a second moment minus the squared mean would cancel catastrophically in
float32). A frame is one launch, or several over consecutive samples when progress is shown.
`max_depth` has Mitsuba's meaning (number of path segments; 1 = directly visible emission,
2 = direct illumination, -1 = unbounded up to MAX_SEGMENTS). Russian roulette (Mitsuba's rule,
off by default) starts at `rr_depth`. `strategy` selects MIS (default), NEE-only or BSDF-only,
three estimators of the same integral used to cross-check each other. `nee.samples` light
samples are taken at every vertex (Mitsuba's `direct` integrator calls them emitter samples);
with MIS they are combined with the one BSDF sample by the balance heuristic over
N p_light + p_bsdf. Sample 0 uses the path's own stream; sample j > 0 the stream of stage
STAGE_PATH_NEE + j, so images with one light sample do not change. With `emission.rays` n > 1
the emission seen directly is the mean over the sample's camera ray and n - 1 more
(common/primary_hits.py), and the path's own hit contributes to that mean, not to L.
The path's steps (light connection, emission MIS weight, scattering, Russian roulette) are the
device functions of device/path_steps.py, which ReSTIR PT's base path and replay also call.
"""
import dataclasses

import numpy as np
import warp as wp

from ..device.bounce import bounce_dim, material_at, nee_at, scatter_at, shading_frame
from ..device.bsdf import bsdf_is_delta_only
from ..device.camera import Camera, camera_u, generate_ray, lens_u
from ..device.color import max3
from ..device.intersect import T_MAX, trace_closest
from ..device.lights import env_eval, env_pdf, triangle_emission, triangle_light_pdf
from ..device.path_steps import emission_mis_weight, rr_survival_probability
from ..device.rng import rng_key, rng_uniform
from ..device.sampling import to_local
from ..device.scene_device import SceneDevice
from ..device.streams import DIM_RR, DIMS_PER_SAMPLE, MAX_NEE_SAMPLES, MAX_SEGMENTS, STAGE_PATH_NEE, STAGE_PATH_TRACE
from ..device.types import ENV_NONE, STRATEGY_BSDF, STRATEGY_MIS, STRATEGY_NEE
from ..film import Welford, welford_add
from ..settings import Settings, setting
from .base import Integrator
from .common.events import EventCounts, output_events, packed_events, ray_events
from .common.emission_edges import VARIED, edge_choice, edge_launch, edge_record, emission_sum, seen
from .common.primary_hits import emission_rays, emission_seen, lattice_emission

SAMPLES_PER_LAUNCH = 1 << 21  # pixel samples in one launch of a frame that can be stopped (sample_batches)

STRATEGIES = {"mis": STRATEGY_MIS, "nee": STRATEGY_NEE, "bsdf": STRATEGY_BSDF}


@wp.struct
class PTParams:
    seed: wp.uint32
    frame: wp.uint32
    spp: int
    sample_begin: int  # this launch renders samples [sample_begin, sample_end) of the frame's spp
    sample_end: int
    max_depth: int
    rr_depth: int
    use_rr: int
    strategy: int
    hide_emitters: int
    nee_samples: int   # light samples per vertex, N
    emission_rays: int  # camera rays per sample for the emission seen directly (common/primary_hits.py)
    emission_adaptive: int  # those rays only near emitters' edges and small emitters (emission_edges.py)


@wp.struct
class PathResult:
    L: wp.vec3
    rays: int
    Le0: wp.vec3  # the emission seen directly, left out of L when emission.rays > 1 (the kernel averages it)


def make_path_trace_kernel(several_light_samples: bool):
    """The path tracing kernel, with or without the loop over light samples 2..N at each vertex.

    A compile-time choice: on the CPU the loop costs the one-light-sample kernel about 14% of its
    time even when it runs no iteration (measured at 192x192, 8 spp, Cornell box), so the
    default kernel is built without it.
    """

    @wp.func
    def path_radiance(scene: SceneDevice, params: PTParams, o_in: wp.vec3, d_in: wp.vec3, pixel: wp.uint32, key: wp.uint32,
                      base: wp.uint32) -> PathResult:
        rays = int(0)
        L = wp.vec3(0.0)
        beta = wp.vec3(1.0)
        o = o_in
        d = d_in
        prev_pdf = float(1.0)
        prev_delta = int(1)
        eta = float(1.0)
        max_depth = wp.where(params.max_depth < 0, MAX_SEGMENTS, wp.min(params.max_depth, MAX_SEGMENTS))
        Le0 = wp.vec3(0.0)
        depth = int(0)
        while True:
            hit = trace_closest(scene, o, d, T_MAX)
            rays += 1
            visible_emitter = not (params.hide_emitters != 0 and depth == 0)
            if depth == 0 and visible_emitter and params.emission_rays > 1:
                Le0 = emission_seen(scene, hit, d)  # the kernel averages it with the other rays'
                visible_emitter = False
            # ---- escaped: environment emission
            if hit.valid == 0:
                if scene.env_kind != ENV_NONE and visible_emitter:
                    w = emission_mis_weight(prev_delta, prev_pdf, env_pdf(scene, d), params.nee_samples, params.strategy)
                    L += wp.cw_mul(beta, env_eval(scene, d)) * w
                break
            # ---- emission found by BSDF sampling (or seen directly)
            Le = triangle_emission(scene, hit.tri, hit.ns, -d)
            if max3(Le) > 0.0 and visible_emitter:
                w = emission_mis_weight(prev_delta, prev_pdf, triangle_light_pdf(scene, hit.tri, hit.ng, d, hit.t),
                                        params.nee_samples, params.strategy)
                L += wp.cw_mul(beta, Le) * w
            if depth + 1 >= max_depth:
                break
            frame = shading_frame(scene, hit, -d)
            mat = material_at(scene, hit, frame)
            wi = to_local(frame, -d)
            dim = base + bounce_dim(depth, 0)  # this vertex's numbers (device/bounce.py; RR below)
            # ---- next-event estimation: N light samples, each weighted 1/N (with MIS: balance over N p_L + p_B;
            # BSDF-only: the delta lights' samples alone, which no BSDF sample can reach)
            if bsdf_is_delta_only(mat) == 0 and (params.strategy != STRATEGY_BSDF or scene.num_delta_lights > 0):
                c = nee_at(scene, hit, mat, frame, wi, key, base, depth, params.nee_samples, params.strategy)
                nee = c.L
                rays += c.rays
                if wp.static(several_light_samples):
                    for j in range(1, params.nee_samples):
                        key_j = rng_key(params.seed, params.frame, wp.uint32(STAGE_PATH_NEE + j), pixel)
                        cj = nee_at(scene, hit, mat, frame, wi, key_j, base, depth, params.nee_samples,
                                    params.strategy)
                        nee += cj.L
                        rays += cj.rays
                L += wp.cw_mul(beta, nee)
            # ---- BSDF sampling
            sc = scatter_at(hit, mat, frame, wi, key, base, depth)
            if sc.valid == 0:
                break
            beta = wp.cw_mul(beta, sc.bs.weight)
            if max3(beta) <= 0.0:
                break
            d = sc.d
            o = sc.o
            prev_pdf = sc.bs.pdf
            prev_delta = sc.bs.is_delta
            eta = eta * sc.bs.eta
            depth += 1
            # ---- Russian roulette (Mitsuba's rule; off by default)
            if params.use_rr != 0 and depth >= params.rr_depth:
                q = rr_survival_probability(beta, eta)
                if rng_uniform(key, dim + wp.uint32(DIM_RR)) >= q:
                    break
                beta = beta / q
        res = PathResult()
        res.L = L
        res.rays = rays
        res.Le0 = Le0
        return res

    @wp.kernel
    def path_trace_kernel(
        offset: int,
        scene: SceneDevice,
        camera: Camera,
        params: PTParams,
        edges_previous: wp.array(dtype=wp.vec2),
        edge_marks: wp.array(dtype=wp.uint8),
        frame_mean: wp.array(dtype=wp.vec3),
        frame_m2: wp.array(dtype=wp.vec3),
        edges_current: wp.array(dtype=wp.vec2),
        events: wp.array(dtype=EventCounts),
    ):
        pixel = wp.tid() + offset
        key = rng_key(params.seed, params.frame, wp.uint32(STAGE_PATH_TRACE), wp.uint32(pixel))
        acc = Welford()
        if params.sample_begin > 0:  # a later part of the frame: resume the pixel's running moments
            acc.mean = frame_mean[pixel]
            acc.m2 = frame_m2[pixel]
            acc.n = params.sample_begin
        rays = int(0)
        choice = edge_choice(edges_previous, edge_marks, camera, pixel, params.emission_rays,
                             params.emission_adaptive)
        n = choice.rays
        record = float(VARIED)  # what this launch's rays saw of the emission (emission_edges.py)
        for s in range(params.sample_begin, params.sample_end):
            base = wp.uint32(s) * wp.uint32(DIMS_PER_SAMPLE)
            u = camera_u(params.seed, params.frame, pixel, s)
            u_lens = lens_u(params.seed, params.frame, pixel, s)
            ray = generate_ray(camera, pixel % camera.width, pixel // camera.width, u, u_lens)
            res = path_radiance(scene, params, ray.o, ray.d, wp.uint32(pixel), key, base)
            rays += res.rays
            L = res.L * ray.weight
            if params.emission_rays > 1 and params.hide_emitters == 0:
                first = emission_sum(res.Le0)
                if s > params.sample_begin:
                    first = seen(record, res.Le0)
                extra = lattice_emission(scene, camera, pixel, u, u_lens, n, first)
                record = extra.record
                L += (res.Le0 * ray.weight + extra.Le) / float(n)
                rays += n - 1
            acc = welford_add(acc, L)
        if params.emission_rays > 1 and params.emission_adaptive != 0 and params.hide_emitters == 0:
            edges_current[pixel] = edge_record(choice, record)
        frame_mean[pixel] = acc.mean
        frame_m2[pixel] = acc.m2
        if params.sample_end == params.spp:  # a non-finite mean is counted once, when the frame is done
            events[pixel] = packed_events(output_events(acc.mean, rays))
        else:
            events[pixel] = packed_events(ray_events(rays))

    return path_trace_kernel


path_trace_kernel = make_path_trace_kernel(False)
path_trace_kernel_light_samples = make_path_trace_kernel(True)  # nee.samples > 1


@dataclasses.dataclass
class PathTracerSettings(Settings):
    strategy: str = setting("strategy", "mis", "mis: NEE and BSDF sampling with the balance heuristic; nee: NEE "
                            "only; bsdf: BSDF sampling only")
    rr: bool = setting("rr", False, "Russian roulette from the scene's rr_depth (Mitsuba's rule)")
    nee_samples: int = setting("nee.samples", 1, "light samples per vertex (Mitsuba's direct integrator's "
                               "emitter samples)", static=True)  # 1 or more: two kernels


class PathTracer(Integrator):
    name = "pt"
    STAGES = ("path_trace",)
    KERNELS = (path_trace_kernel, path_trace_kernel_light_samples)
    Settings = PathTracerSettings
    DESCRIPTION = "reference path tracer (NEE + BSDF sampling with MIS), Mitsuba's max_depth"

    @staticmethod
    def check_settings(settings: PathTracerSettings) -> None:
        from ..config import ConfigError

        if settings.strategy not in STRATEGIES:
            raise ConfigError(f"strategy must be one of {', '.join(STRATEGIES)}")
        if not 1 <= settings.nee_samples <= MAX_NEE_SAMPLES:
            raise ConfigError(f"nee.samples must be in [1, {MAX_NEE_SAMPLES}]")

    def allocate(self) -> None:
        self.frame_mean = self.buffer("frame_mean", wp.vec3)
        self.frame_m2 = self.buffer("frame_m2", wp.vec3)   # sum of squared deviations (Welford)

    def params(self, frame: int) -> PTParams:
        s = self.settings
        p = PTParams()
        p.seed = wp.uint32(s.seed & 0xFFFFFFFF)
        p.frame = wp.uint32(frame)
        p.spp = int(s.spp)
        p.sample_begin = 0
        p.sample_end = p.spp
        p.max_depth = int(s.max_depth)
        p.rr_depth = int(s.rr_depth)
        p.use_rr = int(bool(s.rr))
        p.strategy = int(STRATEGIES[s.strategy])
        p.hide_emitters = int(bool(s.hide_emitters))
        p.nee_samples = int(s.nee_samples)
        p.emission_rays = emission_rays(self)
        p.emission_adaptive = 0  # set per launch (render_samples)
        return p

    # The kernel averages a frame's samples itself (Welford in frame_mean, frame_m2): one launch
    # per frame, or with a progress hook a few launches over consecutive samples (the same numbers
    # in the same order, so the same image but for emission.adaptive's records, which each launch
    # renews) so that long frames show progress; and when a stop can be asked for (Ctrl-C), at
    # most SAMPLES_PER_LAUNCH pixel samples a launch, so that it is honoured within about a second.
    def sample_batches(self, spp: int) -> list:
        parts = min(spp, 8) if self.on_samples is not None else 1
        if self.stop_requested is not None:
            parts = min(spp, max(parts, -(-spp * self.num_pixels // SAMPLES_PER_LAUNCH)))
        bounds = [spp * i // parts for i in range(parts + 1)]
        return list(zip(bounds[:-1], bounds[1:]))

    def render_samples(self, frame: int, begin: int, end: int, camera) -> None:
        kernel = path_trace_kernel if self.settings.nee_samples == 1 else path_trace_kernel_light_samples
        p = self.params(frame)
        p.sample_begin, p.sample_end = begin, end
        with edge_launch(self, "path_trace", camera, begin == 0) as e:
            p.emission_adaptive = e.adaptive
            self.run_stage("path_trace", kernel, [self.dscene.scene, camera, p, e.previous, e.marks],
                           [self.frame_mean, self.frame_m2, e.current], nonfinite="nonfinite_outputs",
                           new_call=e.new_call)

    def frame_moments(self):
        shape = (self.height, self.width, 3)
        var = self.frame_m2.numpy() / np.float32(self.settings.spp)
        return self.frame_mean.numpy().reshape(shape), var.reshape(shape)
