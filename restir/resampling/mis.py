"""Resampling MIS weights over a fixed set of techniques (docs/validation.md#what-has-to-hold,
conditions 3 and 5).

Notation for one input sample y in the current (canonical) domain c, from technique i:
  d_j(y) = p_hat_j(T_{c->j}(y)) * J_{c->j}(y) * M_j   the density technique j would assign to y
                                                       (its own-domain target seen through the
                                                       shift, times its confidence); 0 when the
                                                       shift fails or the target is 0.
The set of techniques is fixed by geometry before any sample is drawn; a failed shift or a
zero target makes a density 0, it never removes the technique.

- Generalized balance (Talbot): m_i(y) = d_i(y) / sum_j d_j(y).
- Pairwise (Bitterli 2022 thesis; as ReSTIR PT codes it): with k the *configured* neighbour
  count and V the number of neighbours valid by geometry, the neighbour weight is
      m_i = d_i / (d_i + d_c / k)
  and the canonical weight is 1 + sum_i (d_c/k) / (d_i(T(x_c)) + d_c/k), everything divided by
  (V + 1) at finalisation. For every y the weights sum to exactly 1.
- Constant-binary: m_i(y) = M_i [d_i(y) > 0] / sum_j M_j [d_j(y) > 0] (unbiased, no balance).
- Constant 1/M: m_i = M_i / sum_j M_j regardless of support: BIASED where supports differ;
  available only for comparison, behind an explicit switch.
"""
import warp as wp

MAX_TECHNIQUES = 33  # canonical + up to 32 neighbours
techniques_vec = wp.types.vector(length=MAX_TECHNIQUES, dtype=float)


@wp.func
def balance_weight(d: techniques_vec, n: int, i: int) -> float:
    """Generalized balance heuristic for technique i among the first n; 0 when all are 0."""
    total = float(0.0)
    for j in range(n):
        total += d[j]
    if total <= 0.0:
        return 0.0
    return d[i] / total


@wp.func
def pairwise_neighbor_weight(d_i: float, d_c: float, k: int) -> float:
    """Weight of neighbour i's sample y: d_i = its own-domain density seen from the canonical
    domain (p_hat_i(x_i) / J_{i->c} * M_i), d_c = p_hat_c(y) * M_c."""
    a = d_c / float(k)
    if d_i <= 0.0:
        return 0.0
    return d_i / (d_i + a)


@wp.func
def pairwise_canonical_term(d_c: float, d_i: float, k: int) -> float:
    """One neighbour's share of the canonical weight: d_c = p_hat_c(x_c) * M_c,
    d_i = p_hat_i(T_{c->i}(x_c)) * J_{c->i} * M_i (0 if the shift fails: the full share)."""
    a = d_c / float(k)
    if d_i <= 0.0:
        return 1.0
    return a / (d_i + a)


@wp.struct
class PairwiseMIS:
    """Pairwise MIS over a canonical input and neighbours, accumulated as the pass streams them.

    k: the configured neighbour count (fixed before sampling; enters every weight); V: the
    neighbours valid by geometry so far; m_c: the canonical input's weight 1 + sum of its shares;
    m_i: the weight of the neighbour added last. The pass finalises with normalization V + 1
    (`pairwise_normalization`), after which the weights of every technique at any y sum to 1.
    """
    k: int
    V: int
    m_c: float
    m_i: float


@wp.func
def pairwise_init(k: int) -> PairwiseMIS:
    acc = PairwiseMIS()
    acc.k = k
    acc.V = 0
    acc.m_c = 1.0
    acc.m_i = 0.0
    return acc


@wp.func
def pairwise_add_neighbor(acc: PairwiseMIS, d_i_at_y: float, d_c_at_y: float, d_c_at_xc: float,
                          d_i_at_xc: float) -> PairwiseMIS:
    """Add one neighbour i that is valid by geometry (whatever its reservoir holds).

    y = T_{i->c}(x_i) is its sample in the canonical domain: d_i_at_y = p_hat_i(x_i) / J_{i->c} * M_i,
    d_c_at_y = p_hat_c(y) * M_c. x_c is the canonical sample: d_c_at_xc = p_hat_c(x_c) * M_c,
    d_i_at_xc = p_hat_i(T_{c->i}(x_c)) * J_{c->i} * M_i (0 when that shift fails).
    Returns the accumulator with V + 1, the canonical share added, and m_i set.
    """
    out = acc
    out.V = acc.V + 1
    out.m_i = pairwise_neighbor_weight(d_i_at_y, d_c_at_y, acc.k)
    out.m_c = acc.m_c + pairwise_canonical_term(d_c_at_xc, d_i_at_xc, acc.k)
    return out


@wp.func
def pairwise_normalization(acc: PairwiseMIS) -> float:
    return float(acc.V + 1)


@wp.func
def talbot_weight2(d_0: float, d_1: float, i: int) -> float:
    """Generalized balance (Talbot) weight of technique i of two: d_i / (d_0 + d_1); 0 when both are 0."""
    total = d_0 + d_1
    if total <= 0.0:
        return 0.0
    return wp.where(i == 0, d_0, d_1) / total


@wp.func
def constant_binary_weight(d: techniques_vec, M: techniques_vec, n: int, i: int) -> float:
    total = float(0.0)
    for j in range(n):
        if d[j] > 0.0:
            total += M[j]
    if d[i] <= 0.0 or total <= 0.0:
        return 0.0
    return M[i] / total


@wp.func
def constant_weight_biased(M: techniques_vec, n: int, i: int) -> float:
    """M_i / sum M_j: biased where supports differ (comparison only)."""
    total = float(0.0)
    for j in range(n):
        total += M[j]
    if total <= 0.0:
        return 0.0
    return M[i] / total
