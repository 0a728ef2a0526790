"""Streaming resampled importance sampling (Talbot 2005; GRIS, Lin et al. 2022).

`RisState` is the in-flight state of one resampling pass; it never leaves the pass. A stored
reservoir keeps W (the unbiased contribution weight) instead of w_sum; the two are different
fields of different types, so a partly built state cannot be read as a finished reservoir.

For inputs i = 1..n with samples y_i in the current domain, resampling weights
w_i = m_i(y_i) * p_hat(y_i) * J_i * W_i select y with probability w_i / w_sum, and
W = w_sum / p_hat(y) (times 1/normalization where the MIS weights are normalized at the end,
as pairwise MIS's 1/(V+1)). Inputs with zero weight are still inputs: they add their confidence
M and can never be selected. Non-finite weights are counted and treated as zero, not hidden.
"""
import warp as wp


@wp.struct
class RisState:
    w_sum: float       # running sum of resampling weights
    p_hat: float       # target of the selected sample in this pass's domain
    M: float           # confidence accumulated from all inputs
    selected: int      # caller's index of the selected input, -1 while none
    nonfinite: int     # inputs whose weight was NaN or inf (counted, then treated as 0)
    zero: int          # inputs whose weight was 0 (kept as inputs; counted for the stats)
    count: int         # inputs streamed


@wp.func
def ris_init() -> RisState:
    s = RisState()
    s.w_sum = 0.0
    s.p_hat = 0.0
    s.M = 0.0
    s.selected = -1
    s.nonfinite = 0
    s.zero = 0
    s.count = 0
    return s


@wp.func
def is_finite(x: float) -> bool:
    return x == x and wp.abs(x) < 3.0e38


@wp.func
def ris_stream(s: RisState, w: float, p_hat: float, M: float, index: int, u: float) -> RisState:
    """Stream one input (resampling weight w, target p_hat of its sample, confidence M).

    u is this input's own uniform number from the pass's resampling stream. Returns the new
    state; the input was selected iff the returned state's `selected` equals `index`.
    """
    r = s
    r.M = s.M + M
    r.count = s.count + 1
    weight = w
    if not is_finite(weight):
        r.nonfinite = s.nonfinite + 1
        weight = 0.0
    if weight <= 0.0:
        r.zero = s.zero + 1
    if weight > 0.0:
        r.w_sum = s.w_sum + weight
        if u * r.w_sum < weight:
            r.selected = index
            r.p_hat = p_hat
    return r


@wp.func
def ris_merge(s: RisState, m: float, p_hat: float, J: float, W: float, M: float, index: int, u: float) -> RisState:
    """Stream one reservoir of another domain (or this one) with its generalized RIS weight
    w = m * p_hat * J * W (Lin et al. 2022, GRIS): m its MIS weight, p_hat the target of its
    sample shifted into this domain, J the shift's Jacobian (1 for the identity shift and for
    the canonical input), W its unbiased contribution weight, M its confidence. A failed shift
    passes J = 0 (or p_hat = 0): the input still counts with its M and is never selected."""
    return ris_stream(s, m * p_hat * J * W, p_hat, M, index, u)


@wp.func
def ris_expected_add(L: wp.vec3, w: float, F: wp.vec3, p_hat: float) -> wp.vec3:
    """L plus one input's term of the pass's expected output, w F(y) / p_hat(y) (the inputs that
    ris_stream zeroes add nothing). Over a pass, sum_i w_i F(y_i) / p_hat(y_i) / normalization is
    the expectation of its output F(Y) W given its inputs (selecting y_i with probability
    w_i / w_sum, W = w_sum / (p_hat(Y) normalization)): the same mean with the selection's noise
    averaged out (Rao-Blackwell). With p_hat = luminance(F) only the colour differs from F(Y) W:
    every term has luminance w_i."""
    if is_finite(w) and w > 0.0 and p_hat > 0.0:
        return L + F * (w / p_hat)
    return L


@wp.func
def ris_contribution_weight(s: RisState, normalization: float) -> float:
    """W = w_sum / (p_hat(y) * normalization); 0 when nothing was selected. A non-finite W is
    returned as it is (never silently zeroed): it surfaces in the stages' non-finite counters."""
    if s.selected < 0 or s.p_hat <= 0.0 or normalization <= 0.0:
        return 0.0
    return s.w_sum / (s.p_hat * normalization)


@wp.struct
class ReservoirWeights:
    """What finalisation gives a stored reservoir besides its sample: W, M and whether a sample
    was selected at all (a reservoir with none keeps its confidence M and has W = 0)."""
    W: float
    M: float
    selected: int


@wp.func
def ris_finalize(s: RisState, normalization: float) -> ReservoirWeights:
    """The end of a resampling pass: W = w_sum / (p_hat(y) * normalization) and M = the summed
    confidences. Each stored reservoir type has one `store` function that copies the selected
    sample and these weights; nothing else writes W or M."""
    f = ReservoirWeights()
    f.W = ris_contribution_weight(s, normalization)
    f.M = s.M
    f.selected = wp.where(s.selected >= 0, 1, 0)
    return f


# A history with "no cap" is still capped at this multiple of the current confidence. The
# official ReSTIR PT code uses 1e30 for its "no cap"; with spatial reuse, whose output
# confidence is the sum of its inputs', M then grows by (1 + V)^rounds per frame until p_hat * M
# overflows float32 (non-finite weights after 32-48 frames). 1e6 frames of history is no
# practical cap, and keeps every p_hat * M finite.
NO_CAP_RATIO = wp.constant(1.0e6)


@wp.func
def cap_history(M_history: float, cap_ratio: float, M_current: float) -> float:
    """The one place a temporal history's confidence is capped: to cap_ratio x the current
    input's (cap_ratio <= 0: "no cap", NO_CAP_RATIO x). The cap is the product even when the
    current confidence is 0 (a pixel with no smooth lobe): the history then gets 0, not an
    unbounded confidence (a cap "0 means no cap" once read it as the latter). The capped value
    must be used consistently in every MIS weight that mentions this input."""
    ratio = cap_ratio
    if ratio <= 0.0:
        ratio = NO_CAP_RATIO
    return wp.min(M_history, ratio * M_current)
