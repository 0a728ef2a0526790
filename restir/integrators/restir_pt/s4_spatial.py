"""Stage 4, spatial reuse: pairwise MIS over the pixel and k neighbours (docs/theory/restir_pt.md#spatial-reuse), in
two forms that compute the same estimator over different neighbours.

`spatial_kernel` (spatial.reciprocal=false; the official pass): k pixels drawn uniformly in a
disk of `spatial_radius` pixels, kept when on screen, with a primary hit and geometrically
similar (G-buffers only, never reservoir contents). For each, its sample is shifted here and this pixel's sample there (the
canonical weight's density): two shifts, each a replay to rcPrev and one visibility ray (done
inline: see s2_temporal.py). Own-domain targets are the stored integrands.
Reads: scene, G-buffer, reservoirs_in. Writes: reservoirs_out (a different buffer: ping-pong),
shifts, events.

`reciprocal_spatial_kernel` (spatial.reciprocal, the default; the reciprocal neighbour selection
of ReSTIR PT Enhanced, Lin et al. 2025): the same pairwise MIS for half the shifts. The two shifts of a
(pixel q, neighbour n) pair are also the two that n needs for q, roles swapped, when n has q as
its neighbour. So neighbour j of every pixel is its partner in the round's j-th pairing
(reuse_domains.reciprocal_partner: a perfect matching of the screen drawn by `pairings_kernel`
from a stream no pixel's samples touch, so the techniques are fixed before any sample), and one
thread makes a pair's two shifts and updates both pixels: k shifts per pixel instead of 2k.
One launch per neighbour j: every pixel is in exactly one pair per launch and the pair's lower
pixel does the work, so no pixel is written twice in a launch and the threads' order cannot
matter (docs/validation.md#level-7-races-and-determinism). Between launches a pixel's resampling
state is the sample chosen so far
(in reservoirs_out) and `sums` (w_sum, M, V): the sample radiance's buffer, which the shade stage
fills only after this pass. The canonical input's weight m_c = 1 + sum_j share_j
(resampling/mis.py) is known only after the last neighbour, so the canonical sample is streamed
in parts: each pair adds it with weight share_j * p_hat * W, the last launch adds the 1 (with
its M). Selecting any part selects the canonical sample, with total probability
m_c p_hat W / w_sum: the estimator of one candidate of weight m_c (weighted reservoir sampling is
exact for split candidates), with other random numbers.
Reads: scene, G-buffer, the pairings, reservoirs_in. Writes: reservoirs_out, sums, shifts, events.
"""
import warp as wp

from ...device.color import luminance
from ...device.rng import rng_key, rng_uniform, rng_uniform2
from ...device.scene_device import SceneDevice
from ...device.streams import (DI_SPATIAL_DIM_CANONICAL, DI_SPATIAL_DIM_OFFSET, DI_SPATIAL_DIM_SELECT,
                               DI_SPATIAL_DIM_SHARE, DI_SPATIAL_DIMS_PER_NEIGHBOR, DI_SPATIAL_DIMS_PER_SAMPLE,
                               PAIRING_DIM_MASK, PAIRING_DIM_SHIFT, STAGE_PT_SPATIAL, STAGE_PT_SPATIAL_PAIRING)
from ...resampling.mis import pairwise_canonical_term, pairwise_normalization
from ...resampling.ris import ris_expected_add, ris_finalize, ris_merge
from ..common.events import EventCounts, PassCounts, packed_counts, packed_events, stage_events
from ..common.gbuffer import GBuffer
from ..common.reuse_domains import NO_PIXEL, reciprocal_pairing, reciprocal_partner, spatial_technique
from ..common.shading import load_shading, similar_surfaces
from ..common.tally import unpacked
from ..path_reuse.domain import domain_at
from ..path_reuse.params import PathReuseParams
from ..path_reuse.path_sample import PathReservoir, store
from ..path_reuse.reuse_pair import (CANONICAL, Reuse, ShiftedIn, ShiftTally, make_reuse_pair, merge_neighbor,
                                     spatial_canonical, spatial_start, tally)
from ..path_reuse.shift import SHIFT_INLINED
from .kernel_module import KERNEL_MODULE


def make_spatial_kernel(shift=SHIFT_INLINED, drop_failed: bool = False, module=None):
    """The spatial kernel over a shift function; drop_failed builds the mutation that leaves
    neighbours whose shift failed out of the technique set (V, M and the canonical weight)."""
    shift_in, _, _, spatial_neighbor = make_reuse_pair(shift, module)

    @wp.kernel(module=module or KERNEL_MODULE)
    def spatial_kernel(offset: int, scene: SceneDevice, params: PathReuseParams, width: int, height: int, gb: GBuffer,
                       reservoirs_in: wp.array(dtype=PathReservoir), reservoirs_out: wp.array(dtype=PathReservoir),
                       expected: wp.array(dtype=wp.vec3), shifts: wp.array(dtype=PassCounts),
                       events: wp.array(dtype=EventCounts)):
        pixel = wp.tid() + offset
        c = reservoirs_in[pixel]
        events[pixel] = packed_events(wp.vec4i(0))
        shifts[pixel] = packed_counts(wp.vec4i(0))
        sc = load_shading(scene, gb, pixel)
        if sc.valid == 0:
            reservoirs_out[pixel] = c
            if params.expected_out != 0:
                expected[pixel] = wp.vec3(0.0)
            return
        key = rng_key(params.seed, params.frame, wp.uint32(STAGE_PT_SPATIAL + params.spatial_round), wp.uint32(pixel))
        base = wp.uint32(params.sample) * wp.uint32(DI_SPATIAL_DIMS_PER_SAMPLE)
        dc = domain_at(sc, params)  # ReSTIR PT's pixels share the frame's parameters
        st = spatial_start(c, params.spatial_k)
        for j in range(params.spatial_k):
            dim = base + wp.uint32(j * DI_SPATIAL_DIMS_PER_NEIGHBOR)
            nb = spatial_technique(scene, gb, rng_uniform2(key, dim + wp.uint32(DI_SPATIAL_DIM_OFFSET)), pixel, width,
                                   height, params.spatial_radius, sc)
            if nb.pixel == NO_PIXEL:
                continue
            r = reservoirs_in[nb.pixel]
            if wp.static(drop_failed):
                if shift_in(scene, r, r.M, c.M, dc).t.valid == 0:
                    continue
            # ---- the neighbour's sample here, and this pixel's sample there
            st = spatial_neighbor(st, scene, c, dc, r, domain_at(nb.sh, params), j,
                                  rng_uniform(key, dim + wp.uint32(DI_SPATIAL_DIM_SELECT)))
        st = spatial_canonical(st, c, rng_uniform(key, base + wp.uint32(DI_SPATIAL_DIM_CANONICAL)))
        reservoirs_out[pixel] = store(st.chosen, ris_finalize(st.s, pairwise_normalization(st.mis)))
        if params.expected_out != 0:  # the last pass: its expected output for the shade stage
            expected[pixel] = st.L / pairwise_normalization(st.mis)
        events[pixel] = packed_events(stage_events(st.s, st.tl.failed, st.tl.rays))
        shifts[pixel] = packed_counts(st.tl.counts)

    return spatial_kernel


spatial_kernel = make_spatial_kernel()


RESUMED = wp.constant(2000)  # `selected` of a state resumed from an earlier launch that holds a sample


@wp.func(inline=True)
def resume(pixel: int, first: bool, c: PathReservoir, k: int, reservoirs_out: wp.array(dtype=PathReservoir),
           sums: wp.array(dtype=wp.vec3), expected: wp.array(dtype=wp.vec3), with_expected: int) -> Reuse:
    """A pixel's resampling state at the start of launch j: fresh (j = 0: nothing is read), or the
    sums and the sample chosen so far, left by the launch before (its counts start at 0: `put`
    adds them to the earlier launches'), and the expected output's sum so far (with_expected)."""
    st = spatial_start(c, k)
    if not first:
        if with_expected != 0:
            st.L = expected[pixel]
        acc = sums[pixel]
        held = reservoirs_out[pixel]
        st.s.w_sum = acc[0]
        st.s.M = acc[1]
        st.mis.V = int(acc[2])
        st.chosen = held
        if acc[0] > 0.0:
            st.s.selected = RESUMED
            st.s.p_hat = luminance(held.F)
    return st


@wp.func(inline=True)
def add_pair(st: Reuse, c: PathReservoir, r: PathReservoir, nbr: ShiftedIn, own_d_i: float, j: int,
             u_select: float, u_share: float) -> Reuse:
    """Neighbour j into the pixel's resampling (merge_neighbor), then the canonical input's share
    of this pair as a part of the canonical candidate (no confidence: the canonical input's M
    comes with its last part; not a zero-weight input of its own either)."""
    out = merge_neighbor(st, c, r, nbr, own_d_i, j, u_select)
    p_c = luminance(c.F)
    share = pairwise_canonical_term(p_c * c.M, own_d_i, out.mis.k)
    zero = out.s.zero
    out.s = ris_merge(out.s, share, p_c, 1.0, c.W, 0.0, CANONICAL, u_share)
    out.L = ris_expected_add(out.L, share * p_c * c.W, c.F, p_c)
    out.s.zero = zero
    if out.s.selected == CANONICAL:
        out.chosen = c
    return out


@wp.func(inline=True)
def put(pixel: int, valid: int, first: bool, last: bool, st: Reuse, c: PathReservoir, u_canonical: float,
        reservoirs_out: wp.array(dtype=PathReservoir), sums: wp.array(dtype=wp.vec3),
        expected: wp.array(dtype=wp.vec3), with_expected: int, normalized: bool,
        shifts: wp.array(dtype=PassCounts), events: wp.array(dtype=EventCounts)):
    """Write a pixel's state after its pair of launch j, its counts added to the launches' before;
    after the last, the canonical input's last part and the finished reservoir, and (with_expected)
    the pass's expected output (`normalized` false only in a fault-injected build). A pixel without
    a primary hit keeps its input."""
    if valid == 0:
        if first:
            reservoirs_out[pixel] = c
            events[pixel] = packed_events(wp.vec4i(0))
            shifts[pixel] = packed_counts(wp.vec4i(0))
            if with_expected != 0:
                expected[pixel] = wp.vec3(0.0)
        return
    out = st
    if last:
        p_c = luminance(c.F)
        out.s = ris_merge(out.s, 1.0, p_c, 1.0, c.W, c.M, CANONICAL, u_canonical)
        if out.s.selected == CANONICAL:
            out.chosen = c
        reservoirs_out[pixel] = store(out.chosen, ris_finalize(out.s, pairwise_normalization(out.mis)))
        if with_expected != 0:
            out.L = ris_expected_add(out.L, p_c * c.W, c.F, p_c)
            expected[pixel] = out.L / wp.where(normalized, pairwise_normalization(out.mis), 1.0)
    else:
        reservoirs_out[pixel] = out.chosen
        sums[pixel] = wp.vec3(out.s.w_sum, out.s.M, float(out.mis.V))
        if with_expected != 0:
            expected[pixel] = out.L
    # the counts add up over the launches and are summed once, after the last (reuse_pass's parts)
    ev = stage_events(out.s, out.tl.failed, out.tl.rays)
    sh = out.tl.counts
    if not first:
        ev += unpacked(events[pixel])
        sh += unpacked(shifts[pixel])
    events[pixel] = packed_events(ev)
    shifts[pixel] = packed_counts(sh)


@wp.kernel(module=KERNEL_MODULE)
def pairings_kernel(params: PathReuseParams, pairings: wp.array(dtype=wp.vec4i)):
    """The round's k pairings (thread j: the j-th), drawn from the frame's pairing stream (pixel 0:
    the same for every pixel), before the pass: its launches read them as a fixed input."""
    j = wp.tid()
    key = rng_key(params.seed, params.frame, wp.uint32(STAGE_PT_SPATIAL_PAIRING + params.spatial_round), wp.uint32(0))
    dim = wp.uint32(params.sample) * wp.uint32(DI_SPATIAL_DIMS_PER_SAMPLE) + wp.uint32(j * DI_SPATIAL_DIMS_PER_NEIGHBOR)
    pairings[j] = reciprocal_pairing(params.spatial_radius, rng_uniform2(key, dim + wp.uint32(PAIRING_DIM_MASK)),
                                     rng_uniform2(key, dim + wp.uint32(PAIRING_DIM_SHIFT)))


def make_reciprocal_spatial_kernel(shift=SHIFT_INLINED, drop_failed: bool = False, module=None,
                                   expected_unnormalized: bool = False):
    """The reciprocal spatial kernel over a shift function; drop_failed builds the mutation that
    leaves neighbours whose shift failed out of the technique set (as make_spatial_kernel's),
    expected_unnormalized the one whose expected output is not divided by the pass's
    normalization (V + 1)."""
    normalized = not expected_unnormalized
    shift_in, _, _, _ = make_reuse_pair(shift, module)

    @wp.kernel(module=module or KERNEL_MODULE)
    def reciprocal_spatial_kernel(offset: int, j: int, scene: SceneDevice, params: PathReuseParams, width: int,
                                  height: int, gb: GBuffer, pairings: wp.array(dtype=wp.vec4i),
                                  reservoirs_in: wp.array(dtype=PathReservoir),
                                  reservoirs_out: wp.array(dtype=PathReservoir), sums: wp.array(dtype=wp.vec3),
                                  expected: wp.array(dtype=wp.vec3), shifts: wp.array(dtype=PassCounts),
                                  events: wp.array(dtype=EventCounts)):
        q = wp.tid() + offset
        n = reciprocal_partner(q, width, height, pairings[j])
        if n != NO_PIXEL and n < q:
            return  # the pair's lower pixel updates both
        first = j == 0
        last = j == params.spatial_k - 1
        base = wp.uint32(params.sample) * wp.uint32(DI_SPATIAL_DIMS_PER_SAMPLE)
        dim = base + wp.uint32(j * DI_SPATIAL_DIMS_PER_NEIGHBOR)
        stage = wp.uint32(STAGE_PT_SPATIAL + params.spatial_round)
        key_q = rng_key(params.seed, params.frame, stage, wp.uint32(q))
        c_q = reservoirs_in[q]
        sh_q = load_shading(scene, gb, q)
        ex = params.expected_out
        st_q = resume(q, first, c_q, params.spatial_k, reservoirs_out, sums, expected, ex)
        if n == NO_PIXEL:  # no neighbour j for this pixel (still a technique of the configured k)
            put(q, sh_q.valid, first, last, st_q, c_q, rng_uniform(key_q, base + wp.uint32(DI_SPATIAL_DIM_CANONICAL)),
                reservoirs_out, sums, expected, ex, wp.static(normalized), shifts, events)
            return
        c_n = reservoirs_in[n]
        sh_n = load_shading(scene, gb, n)
        st_n = resume(n, first, c_n, params.spatial_k, reservoirs_out, sums, expected, ex)
        q_uses = sh_q.valid != 0 and sh_n.valid != 0 and similar_surfaces(sh_q, sh_n)
        n_uses = sh_q.valid != 0 and sh_n.valid != 0 and similar_surfaces(sh_n, sh_q)
        into_q = ShiftedIn()  # n's sample shifted to q
        into_n = ShiftedIn()  # q's sample shifted to n
        if q_uses or n_uses:
            into_q = shift_in(scene, c_n, c_n.M, c_q.M, domain_at(sh_q, params))
            into_n = shift_in(scene, c_q, c_q.M, c_n.M, domain_at(sh_n, params))
            if wp.static(drop_failed):
                q_uses = q_uses and into_q.t.valid != 0
                n_uses = n_uses and into_n.t.valid != 0
        # each shift's rays and outcome are counted once, at the pixel it moved a sample into; a
        # failure counts where the shifted sample was an input
        # (docs/validation.md#always-on-diagnostics)
        st_q.tl = tally(ShiftTally(), c_n, into_q.t, into_q.tried, wp.where(q_uses, 1, 0))
        st_n.tl = tally(ShiftTally(), c_q, into_n.t, into_n.tried, wp.where(n_uses, 1, 0))
        key_n = rng_key(params.seed, params.frame, stage, wp.uint32(n))
        # the pair's two shifts serve both pixels: one's "neighbour's sample here" is the other's
        # "own sample there" (into_n.d_c = p_hat_n(T x_q) J M_n = d_n at x_q)
        if q_uses:
            st_q = add_pair(st_q, c_q, c_n, into_q, into_n.d_c, j,
                            rng_uniform(key_q, dim + wp.uint32(DI_SPATIAL_DIM_SELECT)),
                            rng_uniform(key_q, dim + wp.uint32(DI_SPATIAL_DIM_SHARE)))
        if n_uses:
            st_n = add_pair(st_n, c_n, c_q, into_n, into_q.d_c, j,
                            rng_uniform(key_n, dim + wp.uint32(DI_SPATIAL_DIM_SELECT)),
                            rng_uniform(key_n, dim + wp.uint32(DI_SPATIAL_DIM_SHARE)))
        put(q, sh_q.valid, first, last, st_q, c_q, rng_uniform(key_q, base + wp.uint32(DI_SPATIAL_DIM_CANONICAL)),
            reservoirs_out, sums, expected, ex, wp.static(normalized), shifts, events)
        put(n, sh_n.valid, first, last, st_n, c_n, rng_uniform(key_n, base + wp.uint32(DI_SPATIAL_DIM_CANONICAL)),
            reservoirs_out, sums, expected, ex, wp.static(normalized), shifts, events)

    return reciprocal_spatial_kernel


reciprocal_spatial_kernel = make_reciprocal_spatial_kernel()
