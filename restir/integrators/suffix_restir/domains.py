"""Suffix domains: a pixel's resampled prefix end x_P with the direction back toward x_{P-1}
(the prefix G-buffer: triangle, barycentrics, segment length, segment direction) and its prefix
length P, which sets how long a suffix there may be (max_depth - P): a path-reuse `Domain` whose
start vertex is x_P."""
import warp as wp

from ..common.gbuffer import GBuffer
from ..common.shading import load_shading
from ..path_reuse.domain import Domain
from ..path_reuse.params import PathReuseParams
from .params import SRParams
from .prefix import PrefixReservoir, has_prefix, prefix_length
from ...device.scene_device import SceneDevice


@wp.func
def suffix_params(params: SRParams, P: int) -> PathReuseParams:
    p = params.pt
    p.max_depth = params.pt.max_depth - P
    p.first_event = 0
    p.direct_nee = 0  # a suffix resamples every event from its start
    return p


@wp.func
def load_domain(scene: SceneDevice, params: SRParams, prefixes: wp.array(dtype=PrefixReservoir), prefix_gb: GBuffer,
                pixel: int) -> Domain:
    d = Domain()
    r = prefixes[pixel]
    if has_prefix(r):
        d.sh = load_shading(scene, prefix_gb, pixel)
        d.params = suffix_params(params, prefix_length(r.flags))
    return d
