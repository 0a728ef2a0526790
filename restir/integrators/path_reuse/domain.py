"""A shift's destination: the domain a path sample is moved into, a shading point (the path's
first vertex there: x_1 for ReSTIR PT, a prefix end x_P for Suffix ReSTIR) with the domain's
parameters (the depth it holds, which events it owns, the shift kind and rc criteria).

Every method on path reuse builds its domains once per pixel and hands them to the shift and the
reuse pairs, so a new kind of domain (area ReSTIR's camera samples, say) needs no change there.
"""
import warp as wp

from ..common.shading import Shading
from .params import PathReuseParams


@wp.struct
class Domain:
    sh: Shading              # the start vertex (sh.valid = 0: the pixel has none)
    params: PathReuseParams  # the domain's parameters (max_depth: the whole budget left at sh)


@wp.func
def domain_at(sh: Shading, params: PathReuseParams) -> Domain:
    """The domain of a shading point under the given parameters (a primary hit: the frame's)."""
    d = Domain()
    d.sh = sh
    d.params = params
    return d
