"""Stage 5, shading: a pixel's sample of the image, L = direct + F(Y) W x (filter weight).

`direct` is what ReSTIR PT does not resample: ReSTIR DI's output (emission seen directly and
direct light at the primary hit) with direct=restir-di, or the directly seen emission alone with
direct=pt. F already holds the path's visibility (every event was traced, every shift checked).
Reads: reservoirs, direct, filter weights. Writes: sample_L, origins (a one-hot vector: the final
sample came from the pixel's own base path, temporal or spatial reuse; for the stats), events
(NaN/inf outputs counted).
"""
import warp as wp

from ..common.events import EventCounts, PassCounts, output_events, packed_counts, packed_events
from ..path_reuse.path_sample import PathReservoir, holds_path, origin
from .kernel_module import KERNEL_MODULE


@wp.kernel(module=KERNEL_MODULE)
def shade_kernel(offset: int, reservoirs: wp.array(dtype=PathReservoir), direct: wp.array(dtype=wp.vec3),
                 primary_weight: wp.array(dtype=float), sample_L: wp.array(dtype=wp.vec3),
                 origins: wp.array(dtype=PassCounts), events: wp.array(dtype=EventCounts)):
    pixel = wp.tid() + offset
    L = direct[pixel]
    r = reservoirs[pixel]
    o = wp.vec4i(0)
    if holds_path(r) and r.W > 0.0:
        L += r.F * (r.W * primary_weight[pixel])
        o[origin(r.flags)] = 1
    origins[pixel] = packed_counts(o)
    sample_L[pixel] = L
    events[pixel] = packed_events(output_events(L, 0))
