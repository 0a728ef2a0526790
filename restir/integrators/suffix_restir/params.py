"""Per-frame values of the Suffix ReSTIR stages (runtime, not compile-time)."""
import warp as wp

from ..path_reuse.params import PathReuseParams

GATHER_TALBOT = wp.constant(0)    # generalized balance over the neighbours and the canonical technique
GATHER_PAIRWISE = wp.constant(1)  # pairwise between each neighbour and the canonical technique
GATHER_MIS = {"talbot": GATHER_TALBOT, "pairwise": GATHER_PAIRWISE}

# The Warp module of the shipped stage kernels (one module: the prefix, base path and shift code
# they share is compiled once); fault-injected builds go to modules of their own.
KERNEL_MODULE = "suffix_restir"


@wp.struct
class SRParams:
    # the suffixes' ReSTIR PT parameters: shift kind, rc criteria (near_distance scaled with the
    # scene), candidates, max_depth (the whole path's: a suffix domain's budget is max_depth - P),
    # first_event (the first event a prefix leaves to the suffixes' side: 0 or 1, as ReSTIR PT's),
    # the suffix temporal cap and the suffix spatial neighbours/radius/round
    pt: PathReuseParams
    min_prefix: int           # the prefix end's smallest vertex index P (prefix.min_length)
    adaptive: int             # prefix ends one vertex after the first rough bounce (0: exactly at min_prefix)
    avoid_specular_end: int   # adaptive: reject specular-only prefix ends
    avoid_short_end: int      # adaptive: reject prefix ends reached over a short segment
    short_segment: float      # a prefix end reached over a segment this short is rejected (scene units)
    prefix_cap: float         # prefix temporal reuse: history M capped to this x the current M
    suffix_cap: float         # suffix temporal reuse: history M capped to this (absolute; <= 0: none)
    gather_prefixes: int      # N fresh prefixes per pixel
    gather_suffixes: int      # M neighbour suffixes per prefix
    gather_mis: int           # GATHER_TALBOT or GATHER_PAIRWISE
    gather_cap: float         # neighbour confidences capped to this in the gather (absolute)
    canonical_each: int       # a canonical suffix for every gathered prefix (weight 1), not prefix 0's x N
    box_scale: float          # a prefix end's search box half-size = box_scale x its path footprint
    box_half: float           # > 0: every box has this half-size instead (the non-adaptive radius)
    fallback_radius: float    # unfilled gather slots: random pixels in a disk of this radius (px)
