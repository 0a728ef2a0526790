"""The two shifts of a reuse pair and the MIS densities they give: one input i (a spatial
neighbour or the temporal history) and the pixel's canonical sample c, as the temporal and
spatial passes (and the stage-level D1 test) compute them.

- `shift_in`: i's sample x_i shifted into the canonical domain as y = T(x_i), with its
  resampling target p_hat_c(y) and the two densities that i's MIS weight compares at y:
  d_i = p_hat_i(x_i) / J * M_i (technique i) and d_c = p_hat_c(y) * M_c (the canonical one).
  Both are stored times J (the weight is their ratio): a tiny J cannot overflow p_hat_i / J to
  inf, inf / inf = NaN.
- `shift_out`: the canonical sample x_c shifted into i's domain, for the canonical weight:
  d_i(x_c) = p_hat_i(T x_c) * J * M_i.
A failed shift (or an input without a path) leaves its densities 0: the technique stays in the
set with density 0 (docs/validation.md#what-has-to-hold, condition 5). M_i is the confidence the
pass uses for i (the history's
is capped before any weight: cap_history).

On top of them, the resampling both kinds of pass do (`Reuse`: the RIS state, the pairwise MIS
accumulator, the chosen sample, the shift bookkeeping): `temporal_pair` (the canonical and the
history, generalized balance over the two), and `spatial_neighbor` / `spatial_canonical`
(pairwise MIS, neighbours first, then the canonical input with its accumulated weight). Each
domain comes with its own parameters: ReSTIR PT's pixels share one, Suffix ReSTIR's suffix
domains each hold their own length budget.
"""
import warp as wp

from ...device.color import luminance
from ...device.scene_device import SceneDevice
from ...resampling.mis import PairwiseMIS, pairwise_add_neighbor, pairwise_init, talbot_weight2
from ...resampling.ris import RisState, ris_expected_add, ris_init, ris_merge
from .domain import Domain
from .path_sample import ORIGIN_SPATIAL, ORIGIN_TEMPORAL, PathReservoir, holds_path, with_origin
from .shift import ShiftResult, shift_counts, shift_path

CURRENT = wp.constant(0)      # the temporal pass's input indices in its selection
HISTORY = wp.constant(1)
CANONICAL = wp.constant(1000)  # the spatial pass's canonical input (neighbours are 0..k-1)


@wp.struct
class ShiftedIn:
    t: ShiftResult   # the path y in the canonical domain, J, valid
    tried: int       # the input held a path (W > 0), so a shift was made
    p_c: float       # p_hat_c(y)
    d_i: float       # p_hat_i(x_i) M_i        (= the density of technique i at y, times J)
    d_c: float       # p_hat_c(y) M_c J        (= the canonical density at y, times J)


@wp.struct
class ShiftedOut:
    t: ShiftResult
    tried: int
    d_i: float       # p_hat_i(T x_c) J M_i: technique i's density at the canonical sample


@wp.struct
class ShiftTally:
    """A pass's shift bookkeeping per pixel: rays traced, failed shifts of inputs into the pixel
    (the `failed_shifts` counter), and shift_counts' [reconnections tried, succeeded, pure
    replays tried, succeeded] over both directions."""
    rays: int
    failed: int
    counts: wp.vec4i


@wp.func
def tally(t: ShiftTally, r: PathReservoir, res: ShiftResult, tried: int, into_pixel: int) -> ShiftTally:
    """t with one shift of r (made when `tried`) added; a failure counts when the shift brought
    an input into the pixel (into_pixel = 1), not when it took the pixel's sample out."""
    out = t
    if tried != 0:
        out.rays += res.rays
        out.failed += into_pixel * (1 - res.valid)
        out.counts += shift_counts(r, res)
    return out


@wp.struct
class Reuse:
    """A reuse pass's state for one pixel: the resampling, its pairwise MIS accumulator (spatial),
    the chosen input's path (already in this pixel's domain) and the shift bookkeeping."""
    s: RisState
    mis: PairwiseMIS
    chosen: PathReservoir
    tl: ShiftTally
    L: wp.vec3  # sum over the inputs of w F(y) / p_hat(y): the pass's expected output (ris_expected_add)


@wp.func
def spatial_start(c: PathReservoir, k: int) -> Reuse:
    st = Reuse()
    st.s = ris_init()
    st.mis = pairwise_init(k)
    st.chosen = c
    return st


@wp.func
def merge_neighbor(st: Reuse, c: PathReservoir, r: PathReservoir, nbr: ShiftedIn, own_d_i: float, j: int,
                   u: float) -> Reuse:
    """Neighbour j (its reservoir r, its sample shifted here: nbr) into the pairwise resampling of
    c, with own_d_i the neighbour's density at c's sample (d_i(x_c): ShiftedOut.d_i). The
    canonical input's share of the pair is added to the accumulator (st.mis.m_c)."""
    out = st
    out.mis = pairwise_add_neighbor(st.mis, nbr.d_i, nbr.d_c, luminance(c.F) * c.M, own_d_i)
    out.s = ris_merge(st.s, out.mis.m_i, nbr.p_c, nbr.t.J, r.W, r.M, j, u)
    out.L = ris_expected_add(st.L, out.mis.m_i * nbr.p_c * nbr.t.J * r.W, nbr.t.r.F, nbr.p_c)
    if out.s.selected == j:
        out.chosen = with_origin(nbr.t.r, ORIGIN_SPATIAL)
    return out


_pairs: dict = {}


def make_reuse_pair(shift=shift_path, module=None):
    """(shift_in, shift_out, temporal_pair, spatial_neighbor) over a shift function (the shipped one, or a
    mutant's for the mutation tests), built once per shift."""
    if shift in _pairs:
        return _pairs[shift]

    def named(fn: str):  # another shift's build gets keys of its own (one kernel module may hold two builds)
        return None if shift is shift_path else f"reuse_{fn}_{shift.key}"

    # Around the inlined shift the spatial step is inlined too (a kernel calls it in one place, in
    # its loop over neighbours): left out of line by the compiler, each neighbour copied the scene
    # and both domains (Warp passes structs by value); inlined, Suffix ReSTIR's suffix spatial pass
    # took 0.73x as long. Forcing the other three inline made ReSTIR PT's frame 5% slower
    # (docs/changelog.md#speed-functions-that-copied-the-scene-inlined).
    inline = True if getattr(shift, "inlined", False) else None

    @wp.func(module=module, name=named("shift_in"))
    def shift_in(scene: SceneDevice, r: PathReservoir, M_i: float, M_c: float, dc: Domain) -> ShiftedIn:
        out = ShiftedIn()
        if holds_path(r) and r.W > 0.0:
            out.tried = 1
            out.t = shift(scene, r, dc)
            if out.t.valid != 0:
                out.p_c = luminance(out.t.r.F)
                out.d_i = luminance(r.F) * M_i
                out.d_c = out.p_c * M_c * out.t.J
        return out

    @wp.func(module=module, name=named("shift_out"))
    def shift_out(scene: SceneDevice, c: PathReservoir, M_i: float, di: Domain) -> ShiftedOut:
        out = ShiftedOut()
        if holds_path(c) and c.W > 0.0:
            out.tried = 1
            out.t = shift(scene, c, di)
            if out.t.valid != 0:
                out.d_i = luminance(out.t.r.F) * out.t.J * M_i
        return out

    @wp.func(module=module, name=named("temporal_pair"))
    def temporal_pair(scene: SceneDevice, prev_scene: SceneDevice, c: PathReservoir, dc: Domain, r: PathReservoir,
                      Mq: float, dq: Domain, u_current: float, u_history: float) -> Reuse:
        """The canonical input c (domain dc) with the history r (domain dq, confidence Mq, already
        capped): each shifted into the other's domain, generalized balance MIS over the two; c's
        path is traced in dq's frame's scene (prev_scene: the same as `scene` when nothing moved)."""
        st = Reuse()
        hist = shift_in(scene, r, Mq, c.M, dc)
        cur = shift_out(prev_scene, c, Mq, dq)
        st.tl = tally(tally(ShiftTally(), r, hist.t, hist.tried, 1), c, cur.t, cur.tried, 0)
        st.s = ris_init()
        p_c = luminance(c.F)
        m_c = talbot_weight2(p_c * c.M, cur.d_i, CURRENT)
        m_h = talbot_weight2(hist.d_c, hist.d_i, HISTORY)
        st.s = ris_merge(st.s, m_c, p_c, 1.0, c.W, c.M, CURRENT, u_current)
        st.s = ris_merge(st.s, m_h, hist.p_c, hist.t.J, r.W, Mq, HISTORY, u_history)
        st.L = ris_expected_add(ris_expected_add(wp.vec3(0.0), m_c * p_c * c.W, c.F, p_c),
                                m_h * hist.p_c * hist.t.J * r.W, hist.t.r.F, hist.p_c)
        st.chosen = c
        if st.s.selected == HISTORY:
            st.chosen = with_origin(hist.t.r, ORIGIN_TEMPORAL)
        return st

    @wp.func(module=module, name=named("spatial_neighbor"), inline=inline)
    def spatial_neighbor(st: Reuse, scene: SceneDevice, c: PathReservoir, dc: Domain, r: PathReservoir, dn: Domain,
                         j: int, u: float) -> Reuse:
        """Neighbour j (sample r, domain dn, valid by geometry) into the pairwise resampling of c
        (domain dc)."""
        nbr = shift_in(scene, r, r.M, c.M, dc)
        own = shift_out(scene, c, r.M, dn)
        out = merge_neighbor(st, c, r, nbr, own.d_i, j, u)
        out.tl = tally(tally(st.tl, r, nbr.t, nbr.tried, 1), c, own.t, own.tried, 0)
        return out

    _pairs[shift] = (shift_in, shift_out, temporal_pair, spatial_neighbor)
    return _pairs[shift]


@wp.func
def spatial_canonical(st: Reuse, c: PathReservoir, u: float) -> Reuse:
    """The canonical input last, with its accumulated pairwise weight."""
    out = st
    p_c = luminance(c.F)
    out.s = ris_merge(st.s, st.mis.m_c, p_c, 1.0, c.W, c.M, CANONICAL, u)
    out.L = ris_expected_add(st.L, st.mis.m_c * p_c * c.W, c.F, p_c)
    if out.s.selected == CANONICAL:
        out.chosen = c
    return out


shift_in, shift_out, temporal_pair, spatial_neighbor = make_reuse_pair()
