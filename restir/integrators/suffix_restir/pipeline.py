"""Suffix ReSTIR as a pipeline of stages (docs/theory/suffix_restir.md; docs/guide/suffix_restir.md): primary hits,
ReSTIR DI (direct light at the primary hit, unless direct=pt), prefix trace and temporal prefix
reuse, the prefix search structure, suffix trace, suffix temporal and spatial reuse, final gather.

render_sample is the table of contents; each stage is one kernel in its own file.
"""
import dataclasses
import functools
import math

import numpy as np
import warp as wp

from ...device.streams import SR_MAX_GATHER_PREFIXES, SR_MAX_GATHER_SUFFIXES
from ...settings import EMISSION_RAYS_DOC, MUTATION_DOC, setting
from ..common.events import PassCounts
from ..common.gbuffer import LENS_MUTATION, PingPong, allocate_gbuffer
from ..common.mutations import Mutations
from ..common.primary_hits import primary_hits_kernel
from ..common.reuse_domains import resolve_spatial_radius
from ..common.spatial_settings import SpatialReuseSettings, spatial_reuse
from ..path_reuse.direct_light import DISettings, di_component
from ..path_reuse.integrator import PathReuseIntegrator, PathReuseSettings
from .params import GATHER_MIS, SRParams
from .prefix import PrefixReservoir
from .s1_prefix import prefix_kernel
from .s3_suffix import SUFFIX_MUTATIONS, make_suffix_kernel, suffix_kernel
from .s4_suffix_spatial import suffix_spatial_kernel
from .s5_gather import GATHER_MUTATIONS, gather_kernel, make_gather
from .s2_search import SEARCHES, SearchStructure, boxes_kernel, grid_keys_kernel, grid_order_kernel

def _suffix_mutant(mutation: str) -> tuple:
    return make_suffix_kernel(mutation), gather_kernel


def _gather_mutant(mutation: str) -> tuple:
    return suffix_kernel, make_gather(module=f"suffix_restir_{mutation}", mutation=mutation).kernel


# Fault injections for the mutation tests (common/mutations.py), each a build of the (suffix,
# gather) kernels or, for the race, of the pipeline.
MUTATIONS = Mutations((suffix_kernel, gather_kernel), {
    **{m: functools.partial(_suffix_mutant, m) for m in SUFFIX_MUTATIONS},
    **{m: functools.partial(_gather_mutant, m) for m in GATHER_MUTATIONS},
    "spatial_in_place": None,  # the spatial pass writes its own input (race, R2)
    # a thin lens's primary rays rebuilt from the lens's centre (common/gbuffer.py)
    LENS_MUTATION: None,
})


# The suffix spatial reuse's and the gather fallback's radius at 1080 lines ("auto").
SPATIAL_RADIUS_1080 = 30.0


# The official prototype's defaults (docs/theory/suffix_restir.md#what-this-project-computes),
# the spatial radii in pixels (scaled up
# above 1080 lines), but for the direct light, chosen by the denoised equal-time measurement
# (docs/changelog.md#suffix-restir-directpt): in the path reservoirs (direct=pt), not from the prototype's ReSTIR DI
# component: frames 6-13% cheaper, level after the denoiser (within 4% either way over two seeds on
# three scenes; on Veach Ajar, whose direct light at the primary hits is 0.15% of the image, the
# same), accumulated error lower or equal in every run, 60 bytes a pixel less.
# And emission.rays 8: a frame costs 6-9 path-tracer samples but traced one camera ray for the
# emission seen directly; with eight, the glossy Cornell box's denoised error at equal time went
# from 1.72x and 1.96x the path tracer's to 1.16x and 1.13x (two seeds; four rays: 1.31x, 1.32x),
# the frame at 512 lines about 5% dearer (the primary-hit stage 62-71 -> 467 ms of 8.4-8.6 s;
# docs/guide/when_restir_pays.md#the-emission-rays).
@dataclasses.dataclass
class SuffixSettings(PathReuseSettings):
    emission_rays: int = setting("emission.rays", 8, EMISSION_RAYS_DOC)
    direct: str = setting("direct", "pt", "pt: the method's paths own every event, direct light included; "
                          "restir-di: direct light at the primary hit from ReSTIR DI (the di.* settings; the "
                          "official prototype's choice)")
    rc_near_distance: float = setting("rc.near_distance", 0.03, "hybrid: shortest suffix reconnection segment, x "
                                      "the scene's smallest extent")
    rc_roughness: float = setting("rc.roughness", 0.2, "glossy lobes with a linear roughness above this are rough "
                                  "(prefix ends, rc vertices)")
    prefix_min_length: int = setting("prefix.min_length", 1, "the prefix end's smallest vertex index (1: x2 at the "
                                     "earliest)")
    prefix_adaptive: bool = setting("prefix.adaptive", True, "the prefix ends one vertex after the first rough "
                                    "bounce (false: exactly at min_length)")
    prefix_avoid_specular_end: bool = setting("prefix.avoid_specular_end", True, "adaptive prefixes: a "
                                              "specular-only end vertex is rejected (the search goes on)")
    prefix_avoid_short_end: bool = setting("prefix.avoid_short_end", True, "adaptive prefixes: an end vertex "
                                           "reached over a short segment is rejected")
    prefix_short_segment: float = setting("prefix.short_segment", 0.01, "a prefix end reached over a segment this "
                                          "short (x the scene's smallest extent) is rejected")
    prefix_temporal: bool = setting("prefix.temporal", True, "temporal reuse of prefixes (pairwise, K = 1)")
    prefix_temporal_cap: float = setting("prefix.temporal.cap", 50.0, "prefix history confidence capped to this x "
                                         "the current one (<= 0: no cap)")
    suffix_temporal: bool = setting("suffix.temporal", True, "temporal reuse of suffixes (pairwise, K = 1)")
    suffix_temporal_cap: float = setting("suffix.temporal.cap", 50.0, "suffix history confidence capped to this "
                                         "(absolute; <= 0: no cap)")
    suffix_spatial: SpatialReuseSettings = spatial_reuse("suffix.spatial.", radius_at_1080=SPATIAL_RADIUS_1080,
                                                         doc_prefix="suffix ")
    gather_prefixes: int = setting("gather.prefixes", 4, "N: fresh prefixes per pixel in the final gather "
                                   f"(1-{SR_MAX_GATHER_PREFIXES}; the paper evaluates up to 128)")
    gather_suffixes: int = setting("gather.suffixes", 1, "M: neighbour suffixes gathered per prefix "
                                   f"(1-{SR_MAX_GATHER_SUFFIXES})")
    gather_mis: str = setting("gather.mis", "talbot", "talbot (generalized balance over neighbours and the "
                              "canonical suffix) or pairwise")
    gather_cap: float = setting("gather.cap", 50.0, "neighbour confidences capped to this in the gather (absolute; "
                                "<= 0: no cap)")
    gather_radius: float = setting("gather.radius", 2.0, "search box half-size: this x the path footprint camera "
                                   "-> prefix end x the pixel spread angle (raycone), or this x the scene's smallest "
                                   "extent / the larger image side (fixed)")
    gather_radius_type: str = setting("gather.radius_type", "raycone", "raycone (the path's footprint) or fixed")
    gather_fallback_radius: str = setting("gather.fallback_radius", "auto", "unfilled gather slots: random pixels "
                                          "in a disk of this radius; auto: 30 px up to 1080 lines, scaled with the "
                                          "height above")
    gather_search: str = setting("gather.search", "grid", "the prefix search structure: grid (a hashed grid sorted "
                                 "by cell), hashgrid (wp.HashGrid over the box centres) or bvh (wp.Bvh over the "
                                 "boxes); all find the same neighbours")
    gather_canonical_per_prefix: bool = setting("gather.canonical_per_prefix", False, "trace the canonical suffix "
                                                "for every gathered prefix (weight 1) instead of for prefix 0 only, "
                                                "weighted by N")
    debug_mutation: str = setting("debug.mutation", "none", MUTATION_DOC, static=True)  # builds mutant kernels
    di: DISettings = di_component()


# The official prototype's "MMIS" baseline (its render-mode preset 1, PathTracer.cpp, with the
# pass's useMMIS): the final gather alone, over fresh prefixes and fresh suffixes, combined by the
# same MIS, with no prefix resampling, no suffix reuse (temporal or spatial), the reconnection
# shift and no confidence cap (every M is 1). Not a method of its own: these settings of this one
# (docs/guide/suffix_restir.md, "The MMIS baseline").
MMIS_BASELINE = {"shift": "reconnection", "prefix.temporal": False, "suffix.temporal": False,
                 "suffix.spatial.rounds": 0}


class SuffixReSTIR(PathReuseIntegrator):
    name = "suffix-restir"
    STAGES = ("gbuffer", "di.initial_temporal", "di.initial", "di.visibility", "di.temporal", "di.spatial", "di.shade",
              "prefix", "search", "suffix", "suffix_spatial", "gather")
    KERNELS = (primary_hits_kernel, prefix_kernel, boxes_kernel, grid_keys_kernel, grid_order_kernel, suffix_kernel,
               suffix_spatial_kernel, gather_kernel)
    Settings = SuffixSettings
    DESCRIPTION = ("Suffix ReSTIR (conditional RIS): prefix and suffix reuse, a prefix search structure and a final "
                   "gather of suffixes from neighbouring prefixes")
    MUTATIONS = MUTATIONS

    SPATIAL = "suffix_spatial"
    RESERVOIRS = "suffixes"
    # No third suffix buffer: the suffix stage reads the history and writes the other buffer, so
    # the spatial rounds ping-pong between that one and the history's, which is free by then.

    @staticmethod
    def motion_refusal(settings) -> str | None:
        on = [key for key in ("prefix.temporal", "suffix.temporal") if settings.get(key)]
        if not on:
            return None
        return (f"suffix-restir's temporal reuse ({', '.join(on)}) does not yet trace its history in the previous "
                f"frame's scene, so it would be biased where things move: --set {'=false --set '.join(on)}=false")

    @staticmethod
    def check_settings(settings: SuffixSettings) -> None:
        from ...config import ConfigError

        s = settings
        SuffixReSTIR.check_path_settings(s)
        resolve_spatial_radius(s.gather_fallback_radius, SPATIAL_RADIUS_1080, 1)
        if not 1 <= s.gather_prefixes <= SR_MAX_GATHER_PREFIXES:
            raise ConfigError(f"gather.prefixes must be in [1, {SR_MAX_GATHER_PREFIXES}]")
        if not 1 <= s.gather_suffixes <= SR_MAX_GATHER_SUFFIXES:
            raise ConfigError(f"gather.suffixes must be in [1, {SR_MAX_GATHER_SUFFIXES}]")
        if s.gather_mis not in GATHER_MIS:
            raise ConfigError(f"gather.mis must be one of {', '.join(GATHER_MIS)}")
        if s.gather_search not in SEARCHES:
            raise ConfigError(f"gather.search must be one of {', '.join(SEARCHES)}")
        if s.gather_radius_type not in ("raycone", "fixed"):
            raise ConfigError("gather.radius_type must be raycone or fixed")
        if not s.prefix_min_length >= 1:
            raise ConfigError("prefix.min_length must be >= 1")
        for k in ("prefix.short_segment", "gather.radius"):
            if not s.get(k) >= 0.0:
                raise ConfigError(f"{k} must be >= 0")

    def kernels(self) -> tuple:
        return (*self.KERNELS, *MUTATIONS.kernels(self.settings.debug_mutation))

    def allocate(self) -> None:
        s = self.settings
        self.allocate_path_reuse()
        self.fallback_radius = resolve_spatial_radius(s.gather_fallback_radius, SPATIAL_RADIUS_1080,
                                                      self.height)
        if s.gather_fallback_radius == "auto":
            s.gather_fallback_radius = self.fallback_radius
        # prefixes: the resampled ones (this frame's and the previous)
        self.prefixes = PingPong(self.buffer("prefixes", PrefixReservoir), self.buffer("prefixes_prev", PrefixReservoir))
        self.prefix_gbs = PingPong(allocate_gbuffer(self, "prefix_gbuffer", store_rays=True),
                                   allocate_gbuffer(self, "prefix_gbuffer_prev", store_rays=True))
        # the search structure: a box per pixel (centre and half-size; corners for the BVH)
        self.search = SearchStructure()
        self.search.kind = int(SEARCHES[s.gather_search])
        self.search.halves = self.buffer("search.halves", float)
        if self.search.kind == SEARCHES["bvh"]:
            self.lowers = self.buffer("search.lowers", wp.vec3)
            self.uppers = self.buffer("search.uppers", wp.vec3)
        else:  # no corners: empty arrays (the boxes kernel writes them only for the BVH)
            self.lowers = wp.zeros(0, dtype=wp.vec3, device=self.device)
            self.uppers = wp.zeros(0, dtype=wp.vec3, device=self.device)
        n = self.num_pixels
        if self.search.kind == SEARCHES["grid"]:
            # no centres by pixel (the grid's kernels rebuild them from the prefix ends); the
            # sort's keys and values need twice the entries (Warp's radix sort); a table of the
            # next power of two >= half the pixel count (cells hold about 7 boxes each at 800x800, so
            # under a third of its slots are taken)
            table = 1 << max(1, (n // 2 - 1).bit_length())
            self.search.centers = wp.zeros(0, dtype=wp.vec3, device=self.device)
            self.search.keys = self.buffer("search.grid_keys", wp.int32, 2 * n)
            self.search.ids = self.buffer("search.grid_ids", wp.int32, 2 * n)
            self.search.entries = self.buffer("search.grid_entries", wp.vec4)
            self.search.ranges = self.buffer("search.grid_table", wp.vec2i, table)
            self.search.mask = table - 1
        else:
            self.search.centers = self.buffer("search.centers", wp.vec3)
            for name, dtype in (("keys", wp.int32), ("ids", wp.int32), ("entries", wp.vec4), ("ranges", wp.vec2i)):
                setattr(self.search, name, wp.zeros(0, dtype=dtype, device=self.device))
        self.structure = None
        self.gather_slots = self.buffer("gather_slots", PassCounts)
        self.slot_counts = np.zeros(3, np.int64)  # gather slots filled by the search, by the fallback, empty
        host = self.dscene.host
        lo, hi = host.bounds()
        ext = hi - lo
        # the prototype's "sceneRadius": the smallest extent (docs/theory/suffix_restir.md#what-this-project-computes)
        self.scene_radius = float(max(ext.min(), 1e-3 * ext.max()))
        self.far_point = wp.vec3(*(hi + 10.0 * (ext.max() + 1.0)))
        self.spread_angle = math.atan(2.0 * host.camera.tan_half()[1] / self.height)

    def params(self, frame: int, sample: int) -> SRParams:
        s = self.settings
        pt = self.pt_params(frame, sample, float(s.rc_near_distance) * self.scene_radius, s.suffix_temporal_cap)
        p = SRParams()
        p.pt = pt
        p.min_prefix = int(s.prefix_min_length)
        p.short_segment = float(s.prefix_short_segment) * self.scene_radius
        p.prefix_cap = float(s.prefix_temporal_cap)
        p.suffix_cap = float(s.suffix_temporal_cap)
        p.gather_prefixes = int(s.gather_prefixes)
        p.gather_suffixes = int(s.gather_suffixes)
        p.gather_mis = int(GATHER_MIS[s.gather_mis])
        p.gather_cap = float(s.gather_cap)
        p.box_scale = float(s.gather_radius) * self.spread_angle
        p.box_half = 0.0
        if s.gather_radius_type == "fixed":
            p.box_half = float(s.gather_radius) * self.scene_radius / max(self.width, self.height)
        p.adaptive = int(bool(s.prefix_adaptive))
        p.avoid_specular_end = int(bool(s.prefix_avoid_specular_end))
        p.avoid_short_end = int(bool(s.prefix_avoid_short_end))
        p.canonical_each = int(bool(s.gather_canonical_per_prefix))
        p.fallback_radius = float(self.fallback_radius)
        return p

    def build_search(self, p: SRParams) -> None:
        """Stage "search": the boxes, then the structure over them (rebuilt each frame), one timed
        stage. The hash grid's cell width and query radius: the largest box's half-size."""
        sc = self.dscene.scene
        self.run_stage("search", boxes_kernel, [sc, p.box_scale, p.box_half, self.far_point, self.prefixes.current,
                                                self.prefix_gbs.current],
                       [self.search.centers, self.search.halves, self.lowers, self.uppers])
        with self.timer.stage(self.stage_prefix + "search", False):
            if self.search.kind == SEARCHES["bvh"]:
                if self.structure is None:
                    self.structure = wp.Bvh(self.lowers, self.uppers)
                else:
                    self.structure.rebuild()
                self.search.id = self.structure.id
            elif self.search.kind == SEARCHES["grid"]:
                self.build_grid()
            else:
                # A box holding x has its centre within its half-size of x in every axis, so the
                # cells overlapping the cube of the largest half-size around x hold every candidate
                # (Warp's query visits the cells of [x - r, x + r]^3, unfiltered).
                radius = max(float(self.search.halves.numpy().max()), 1e-6 * self.scene_radius)
                if self.structure is None:
                    self.structure = wp.HashGrid(128, 128, 128, device=self.device)
                self.structure.build(self.search.centers, radius)
                self.search.radius = radius
                self.search.id = self.structure.id

    def build_grid(self) -> None:
        """The sorted grid (s2_search.py): the query's half-size r (the largest box's, widened by a
        relative 1e-5 so that rounding cannot leave a candidate's cell out) and cells of 2.02 r
        (so [x - r, x + r] spans at most 2 cells an axis); then each box's slot, a stable sort by
        slot, the boxes copied into that order and the table of each slot's range of entries."""
        g = self.search
        radius = max(float(g.halves.numpy().max()), 1e-6 * self.scene_radius) * (1.0 + 1e-5)
        g.radius = radius
        g.inv_cell = 1.0 / (2.02 * radius)
        sc, ends = self.dscene.scene, self.prefix_gbs.current
        self.run_stage("search", grid_keys_kernel, [sc, ends, g], [g.keys, g.ids], new_call=False)
        wp.utils.radix_sort_pairs(g.keys, g.ids, self.num_pixels, end_bit=g.mask.bit_length() + 1)
        g.ranges.zero_()
        self.run_stage("search", grid_order_kernel, [sc, ends, g, self.num_pixels], [g.entries, g.ranges],
                       new_call=False)

    def resample_sample(self, frame: int, sample: int, direct):
        sc = self.dscene.scene
        suffix, gather = MUTATIONS.kernels(self.settings.debug_mutation)
        gb, res = self.gbuffers, self.reservoirs
        p = self.params(frame, sample)
        history = self.prev_camera is not None
        # ---- prefixes: fresh, resampled with the previous frame's
        temporal = int(bool(self.settings.prefix_temporal and history))
        self.run_stage("prefix", prefix_kernel, [sc, p, temporal, self.current_camera,
                                                 self.prev_camera or self.dscene.camera, gb.current,
                                                 gb.previous, self.prefixes.previous, self.prefix_gbs.previous],
                       [self.prefixes.current, self.prefix_gbs.current])
        self.build_search(p)
        # ---- suffixes at the resampled prefix ends: new, resampled with the previous frame's, then
        # spatial rounds (they write into the history's buffer, free once the suffix stage read it)
        temporal = int(bool(self.settings.suffix_temporal and history))
        self.run_stage("suffix", suffix, [sc, p, temporal, self.current_camera, self.prev_camera or self.dscene.camera,
                                          gb.current, gb.previous, self.prefixes.current, self.prefix_gbs.current,
                                          self.prefixes.previous, self.prefix_gbs.previous, res.previous],
                       [res.current, self.shift_events])
        self.count_shifts("suffix")
        for rd in range(self.settings.suffix_spatial.rounds):
            p.pt.spatial_round = rd
            self.reuse_pass("suffix_spatial", suffix_spatial_kernel,
                            [sc, p, self.width, self.height, self.prefixes.current, self.prefix_gbs.current],
                            self.settings.debug_mutation == "spatial_in_place")
        # ---- the final gather
        self.run_stage("gather", gather,
                       [sc, p, gb.current, self.search, self.prefixes.current, self.prefix_gbs.current, res.current,
                        self.width, self.height, direct, self.primary_weight],
                       [self.sample_L, self.gather_slots, self.shift_events], nonfinite="nonfinite_outputs")
        self.tally.add(("slots",), self.gather_slots)
        self.count_shifts("gather")
        return self.sample_L

    def take_tally(self, key, sums: np.ndarray) -> None:
        if key[0] == "slots":
            self.slot_counts += sums[:3]
        else:
            super().take_tally(key, sums)

    def swap_history(self) -> None:
        """This sample's resampled prefixes and their ends become the next one's history."""
        self.prefixes.swap()
        self.prefix_gbs.swap()

    def stats(self) -> dict:
        """The path-reuse stats (shifts per pass: suffix reuse and the gather) and the gather's
        slots: the fractions filled by the search, by the fallback, and left empty."""
        out = super().stats()
        total = self.slot_counts.sum()
        out["gather_slots"] = {k: float(v / total) if total else 0.0
                               for k, v in zip(("search", "fallback", "empty"), self.slot_counts)}
        return out
