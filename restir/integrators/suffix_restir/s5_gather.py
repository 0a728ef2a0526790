"""Stage "gather", the final gather (docs/theory/suffix_restir.md#the-final-gather;
docs/guide/suffix_restir.md, "The final gather").

Per pixel, N fresh prefixes from the primary hit (their own numbers, drawn independently of every
reservoir of the frame). Prefix i's internal events are summed; if it has an end x_q, its suffix
domain gathers M neighbour suffix reservoirs from the pixels whose resampled prefix ends lie near
x_q (s2_search.py; unfilled slots: random pixels with a prefix end in a screen disk), and prefix 0
also traces the canonical suffix there (M_c = 1). The neighbours' confidences are capped at
gather_cap. MIS over the neighbour techniques and the canonical one (generalized balance by
default; pairwise with the canonical technique as an option), with the canonical technique in
every prefix's weights but sampled only for prefix 0 and weighted by N (docs/theory/suffix_restir.md#the-final-gather):

    L = direct + w_filter (1 / N) sum_i [internal_i + thp_i (sum_j m_j F_i(T Y_j) J W_j + [i = 0] N m_c F_i(X_c) W_c)]

A slot is a technique when its pixel has a prefix end, whatever its suffix reservoir holds: an
empty reservoir or a failed shift gives density 0, never a smaller technique set.
Reads: scene, G-buffer, the search structure, prefixes and their G-buffer, final suffix
reservoirs, direct light, filter weights. Writes: sample_L, slot counts (found by the search, by
the fallback, empty), shift counts, events.
"""
from types import SimpleNamespace

import warp as wp

from ...device.color import luminance
from ...device.rng import hash_combine, rng_key, rng_uniform2
from ...device.scene_device import SceneDevice
from ...device.streams import (SR_FALLBACK_DIMS_PER_PREFIX, SR_MAX_GATHER_PREFIXES, STAGE_SR_GATHER_FALLBACK,
                               STAGE_SR_GATHER_PREFIX, STAGE_SR_GATHER_RIS, STAGE_SR_GATHER_SUFFIX)
from ...resampling.ris import cap_history, ris_finalize, ris_init
from ..common.events import EventCounts, PassCounts, output_events, packed_counts, packed_events
from ..common.gbuffer import GBuffer
from ..common.reuse_domains import spatial_neighbor
from ..common.shading import load_shading
from ..path_reuse.base_path import BasePath, trace_base_path
from ..path_reuse.path_sample import PathReservoir, empty_path, holds_path, store
from ..path_reuse.reuse_pair import ShiftedIn, ShiftTally, make_reuse_pair, tally
from ..path_reuse.shift import shift_path
from .domains import Domain, load_domain, suffix_params
from .params import GATHER_TALBOT, KERNEL_MODULE, SRParams
from .prefix import PrefixReservoir, has_prefix, prefix_end_shading, trace_prefix
from .s2_search import NO_PIXEL, SearchStructure, Slots, nearest_prefix_ends


@wp.func
def fill_slots(s: Slots, params: SRParams, prefixes: wp.array(dtype=PrefixReservoir), pixel: int, width: int,
               height: int, key: wp.uint32, dim: wp.uint32) -> Slots:
    """The slots the search left empty, filled with random pixels of the fallback disk that have
    a prefix end and are not in a slot already (docs/theory/suffix_restir.md#the-prefix-search)."""
    out = s
    for m in range(params.gather_suffixes):
        if out.pixel[m] != NO_PIXEL:
            continue
        n = spatial_neighbor(rng_uniform2(key, dim + wp.uint32(2 * m)), pixel, width, height, params.fallback_radius)
        if n == NO_PIXEL:
            continue
        if not has_prefix(prefixes[n]):
            continue
        taken = bool(False)
        for k in range(params.gather_suffixes):
            if out.pixel[k] == n:
                taken = True
        if not taken:
            out.pixel[m] = n
    return out


@wp.struct
class NeighborTerm:
    """Neighbour slot j's sample shifted into the gathering domain (y: its path there, J, and the
    densities d_i = p_hat_j(Y_j) M_j, d_c = p_hat_i(y) J M_c) and its MIS weight m_j there."""
    y: ShiftedIn
    m: float


def make_gather(shift=shift_path, module=None, mutation: str = "none"):
    """The gather's weights and kernel over a shift, as a namespace (`neighbor_term`,
    `canonical_weight`, `kernel`): the tests evaluate the kernel's own weight functions. A mutation
    builds a fault-injected variant (docs/validation.md#power-checks-the-mutation-table):
    canonical_not_times_n (the canonical suffix
    of prefix 0 not weighted by N: the defect S4), neighbors_over_k1_squared (the neighbour terms
    divided by (V + 1)^2, S4), drop_empty_slots (slots whose reservoir holds no suffix left out of
    the technique set: A3)."""
    shift_in, shift_out, _, _ = make_reuse_pair(shift, module)
    canonical_times_n = mutation != "canonical_not_times_n"
    over_k1_squared = mutation == "neighbors_over_k1_squared"
    drop_empty = mutation == "drop_empty_slots"

    @wp.func(module=module)
    def is_technique(slots: Slots, k: int, suffixes: wp.array(dtype=PathReservoir)) -> bool:
        """Slot k is a technique when the search or the fallback filled it (geometry only)."""
        n = slots.pixel[k]
        if n == NO_PIXEL:
            return False
        if wp.static(drop_empty):
            if not holds_path(suffixes[n]) or suffixes[n].W <= 0.0:
                return False
        return True

    @wp.func(module=module)
    def techniques(slots: Slots, params: SRParams, suffixes: wp.array(dtype=PathReservoir)) -> float:
        V = float(0.0)
        for k in range(params.gather_suffixes):
            if is_technique(slots, k, suffixes):
                V += 1.0
        return V

    @wp.func(module=module)
    def neighbor_density(scene: SceneDevice, params: SRParams, x: PathReservoir, slots: Slots, k: int,
                         prefixes: wp.array(dtype=PrefixReservoir), prefix_gb: GBuffer,
                         suffixes: wp.array(dtype=PathReservoir)) -> float:
        """Neighbour technique k's density of a sample x (x in its own domain's measure):
        p_hat_k(T x) J M_k, M_k capped at gather_cap; 0 where the shift fails."""
        n = slots.pixel[k]
        dk = load_domain(scene, params, prefixes, prefix_gb, n)
        return shift_out(scene, x, cap_history(suffixes[n].M, params.gather_cap, 1.0), dk).d_i

    @wp.func(module=module)
    def neighbor_term(scene: SceneDevice, params: SRParams, dst: Domain, slots: Slots, j: int, r: PathReservoir,
                      prefixes: wp.array(dtype=PrefixReservoir), prefix_gb: GBuffer,
                      suffixes: wp.array(dtype=PathReservoir)) -> NeighborTerm:
        """Slot j's technique with sample r (confidence: slot j's, capped) shifted into dst, and its
        weight: Talbot d_j / (d_j + d_c + sum_{k != j} d_k), or pairwise d_j / (d_j + d_c) / V."""
        t = NeighborTerm()
        n = slots.pixel[j]
        M_j = cap_history(suffixes[n].M, params.gather_cap, 1.0)
        t.y = shift_in(scene, r, M_j, 1.0, dst)
        if t.y.t.valid == 0:
            return t
        if params.gather_mis == GATHER_TALBOT:
            denom = t.y.d_i + t.y.d_c
            for k in range(params.gather_suffixes):
                if k != j and is_technique(slots, k, suffixes):
                    denom += neighbor_density(scene, params, r, slots, k, prefixes, prefix_gb, suffixes)
            if denom > 0.0:
                t.m = t.y.d_i / denom
        else:
            V = techniques(slots, params, suffixes)
            if V > 0.0 and t.y.d_i + t.y.d_c > 0.0:
                t.m = t.y.d_i / (t.y.d_i + t.y.d_c) / V
        return t

    @wp.func(module=module)
    def canonical_weight(scene: SceneDevice, params: SRParams, slots: Slots, xc: PathReservoir,
                         prefixes: wp.array(dtype=PrefixReservoir), prefix_gb: GBuffer,
                         suffixes: wp.array(dtype=PathReservoir)) -> float:
        """The canonical sample's weight (M_c = 1): Talbot d_c / (d_c + sum_k d_k); pairwise the
        sum over neighbours of d_c / (d_c + d_k), divided by V (1 without neighbours)."""
        d_c = luminance(xc.F)
        if d_c <= 0.0:
            return 0.0
        if params.gather_mis == GATHER_TALBOT:
            denom = d_c
            for k in range(params.gather_suffixes):
                if is_technique(slots, k, suffixes):
                    denom += neighbor_density(scene, params, xc, slots, k, prefixes, prefix_gb, suffixes)
            return d_c / denom
        V = techniques(slots, params, suffixes)
        if V <= 0.0:
            return 1.0
        m = float(0.0)
        for k in range(params.gather_suffixes):
            if is_technique(slots, k, suffixes):
                m += d_c / (d_c + neighbor_density(scene, params, xc, slots, k, prefixes, prefix_gb, suffixes))
        return m / V

    @wp.kernel(module=module or KERNEL_MODULE)
    def gather_kernel(offset: int, scene: SceneDevice, params: SRParams, gb: GBuffer, search: SearchStructure,
                      prefixes: wp.array(dtype=PrefixReservoir), prefix_gb: GBuffer,
                      suffixes: wp.array(dtype=PathReservoir), width: int, height: int, direct: wp.array(dtype=wp.vec3),
                      primary_weight: wp.array(dtype=float), sample_L: wp.array(dtype=wp.vec3),
                      slot_counts: wp.array(dtype=PassCounts), shifts: wp.array(dtype=PassCounts),
                      events: wp.array(dtype=EventCounts)):
        pixel = wp.tid() + offset
        L = direct[pixel]
        tl = ShiftTally()
        filled = wp.vec4i(0)
        sc = load_shading(scene, gb, pixel)
        if sc.valid != 0:
            N = params.gather_prefixes
            prefix_key = rng_key(params.pt.seed, params.pt.frame, wp.uint32(STAGE_SR_GATHER_PREFIX), wp.uint32(pixel))
            fallback_key = rng_key(params.pt.seed, params.pt.frame, wp.uint32(STAGE_SR_GATHER_FALLBACK),
                                   wp.uint32(pixel))
            total = wp.vec3(0.0)
            for i in range(N):
                path_id = wp.uint32(params.pt.sample * SR_MAX_GATHER_PREFIXES + i)
                pf = trace_prefix(scene, params, sc, hash_combine(prefix_key, path_id), True)
                tl.rays += pf.rays
                total += pf.internal
                if pf.valid == 0:
                    continue
                dst = Domain()
                dst.sh = prefix_end_shading(scene, pf)
                dst.params = suffix_params(params, pf.length)
                # ---- the technique set: neighbours by prefix-end geometry only
                slots = nearest_prefix_ends(search, pf.hit.p, params.gather_suffixes)
                slots = fill_slots(slots, params, prefixes, pixel, width, height, fallback_key,
                                   path_id * wp.uint32(SR_FALLBACK_DIMS_PER_PREFIX))
                S = wp.vec3(0.0)
                for m in range(params.gather_suffixes):
                    if slots.pixel[m] == NO_PIXEL:
                        filled[2] += 1
                        continue
                    filled[wp.where(m < slots.found, 0, 1)] += 1
                    r = suffixes[slots.pixel[m]]
                    t = neighbor_term(scene, params, dst, slots, m, r, prefixes, prefix_gb, suffixes)
                    tl = tally(tl, r, t.y.t, t.y.tried, 1)
                    S += t.y.t.r.F * (t.y.t.J * r.W * t.m)
                if wp.static(over_k1_squared):
                    V = techniques(slots, params, suffixes)
                    S = S / ((V + 1.0) * (V + 1.0))
                # ---- the canonical suffix: prefix 0 only, weighted by N (or every prefix, weight 1)
                if i == 0 or params.canonical_each != 0:
                    skey = hash_combine(rng_key(params.pt.seed, params.pt.frame, wp.uint32(STAGE_SR_GATHER_SUFFIX),
                                                wp.uint32(pixel)), path_id)
                    rkey = hash_combine(rng_key(params.pt.seed, params.pt.frame, wp.uint32(STAGE_SR_GATHER_RIS),
                                                wp.uint32(pixel)), path_id)
                    xc = canonical_suffix(scene, dst, skey, rkey)
                    tl.rays += xc.rays
                    if holds_path(xc.r) and xc.r.W > 0.0:
                        m_c = canonical_weight(scene, params, slots, xc.r, prefixes, prefix_gb, suffixes)
                        n_c = float(N)
                        if params.canonical_each != 0 or not wp.static(canonical_times_n):
                            n_c = 1.0
                        S += xc.r.F * (xc.r.W * m_c * n_c)
                total += wp.cw_mul(pf.thp, S)
            L += total * (primary_weight[pixel] / float(N))
        sample_L[pixel] = L
        slot_counts[pixel] = packed_counts(filled)
        shifts[pixel] = packed_counts(tl.counts)
        events[pixel] = packed_events(output_events(L, tl.rays))

    return SimpleNamespace(kernel=gather_kernel, neighbor_term=neighbor_term, canonical_weight=canonical_weight,
                           is_technique=is_technique)


@wp.struct
class Canonical:
    r: PathReservoir
    rays: int


@wp.func
def canonical_suffix(scene: SceneDevice, dst: Domain, path_key: wp.uint32, ris_key: wp.uint32) -> Canonical:
    """A fresh suffix from the gathering prefix's end (streaming RIS over its events, M = 1)."""
    acc = BasePath()
    acc.s = ris_init()
    acc.r = empty_path()
    acc = trace_base_path(scene, dst.params, dst.sh, path_key, ris_key, 0, acc)
    c = Canonical()
    c.r = store(acc.r, ris_finalize(acc.s, 1.0))
    c.rays = acc.rays
    return c


GATHER_MUTATIONS = ("canonical_not_times_n", "neighbors_over_k1_squared", "drop_empty_slots")
gather = make_gather()
gather_kernel = gather.kernel
