"""Stage 5, shading: a pixel's sample of the image, L = direct + F(Y) W x (filter weight), or
with shade.expected L = direct + E x (filter weight), E the last resampling pass's expected
output given its inputs (Reuse.L; resampling/ris.py, ris_expected_add), which that pass wrote.

`direct` is what ReSTIR PT does not resample: ReSTIR DI's output (emission seen directly and
direct light at the primary hit) with direct=restir-di, or the directly seen emission alone with
direct=pt. F already holds the path's visibility (every event was traced, every shift checked).
Reads: reservoirs, direct, filter weights, the expected output. Writes: sample_L, origins (a one-hot vector: the final
sample came from the pixel's own base path, temporal or spatial reuse; for the stats), events
(NaN/inf outputs counted).
"""
import warp as wp

from ..common.events import EventCounts, PassCounts, output_events, packed_counts, packed_events
from ..path_reuse.path_sample import PathReservoir, holds_path, origin
from .kernel_module import KERNEL_MODULE


@wp.kernel(module=KERNEL_MODULE)
def shade_kernel(offset: int, reservoirs: wp.array(dtype=PathReservoir), direct: wp.array(dtype=wp.vec3),
                 primary_weight: wp.array(dtype=float), expected: wp.array(dtype=wp.vec3), use_expected: int,
                 sample_L: wp.array(dtype=wp.vec3), origins: wp.array(dtype=PassCounts),
                 events: wp.array(dtype=EventCounts)):
    pixel = wp.tid() + offset
    L = direct[pixel]
    r = reservoirs[pixel]
    o = wp.vec4i(0)
    if holds_path(r) and r.W > 0.0:
        if use_expected == 0:
            L += r.F * (r.W * primary_weight[pixel])
        o[origin(r.flags)] = 1
    if use_expected != 0:
        L += expected[pixel] * primary_weight[pixel]
    origins[pixel] = packed_counts(o)
    sample_L[pixel] = L
    events[pixel] = packed_events(output_events(L, 0))
