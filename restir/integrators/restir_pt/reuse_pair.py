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
set with density 0 (TESTING.md 5.0 (v)). M_i is the confidence the pass uses for i (the history's
is capped before any weight: cap_history).
"""
import warp as wp

from ...device.color import luminance
from ...device.scene_device import SceneDevice
from ..common.shading import Shading
from .params import PTRParams
from .path_sample import PathReservoir, holds_path
from .shift import ShiftResult, shift_counts, shift_path


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


_pairs: dict = {}


def make_reuse_pair(shift=shift_path, module=None):
    """(shift_in, shift_out) over a shift function (the shipped one, or a
    mutant's for the mutation tests), built once per shift."""
    if shift in _pairs:
        return _pairs[shift]

    @wp.func(module=module)
    def shift_in(scene: SceneDevice, params: PTRParams, r: PathReservoir, M_i: float, M_c: float,
                 sc: Shading) -> ShiftedIn:
        out = ShiftedIn()
        if holds_path(r) and r.W > 0.0:
            out.tried = 1
            out.t = shift(scene, params, r, sc)
            if out.t.valid != 0:
                out.p_c = luminance(out.t.r.F)
                out.d_i = luminance(r.F) * M_i
                out.d_c = out.p_c * M_c * out.t.J
        return out

    @wp.func(module=module)
    def shift_out(scene: SceneDevice, params: PTRParams, c: PathReservoir, M_i: float, si: Shading) -> ShiftedOut:
        out = ShiftedOut()
        if holds_path(c) and c.W > 0.0:
            out.tried = 1
            out.t = shift(scene, params, c, si)
            if out.t.valid != 0:
                out.d_i = luminance(out.t.r.F) * out.t.J * M_i
        return out

    _pairs[shift] = (shift_in, shift_out)
    return _pairs[shift]


shift_in, shift_out = make_reuse_pair()
