"""Stage 2, visibility (only with visibility-aware targets, `visibility = reuse`): one shadow
ray for the initial sample; an occluded sample keeps its confidence but gets W = 0.

Why this is unbiased: with W' = W V(y), E[g(y) W'] = integral of g V over the light points, so W'
is an unbiased contribution weight for the target p_hat V, whose support is exactly the light
points visible from this pixel. Every later stage then resamples with p_hat V, so each
technique's support and its target's support agree (Bitterli et al. 2020, Sec. 4's visibility
reuse; here with visibility in the reuse targets too, which keeps it unbiased).
Fused with stage 1 and temporal reuse by default (s3_temporal.py).
Reads: scene, G-buffer, reservoirs_in. Writes: reservoirs_out (a different buffer), events.
"""
import warp as wp

from ...device.scene_device import SceneDevice
from ..common.events import EventCounts, packed_events, ray_events
from ..common.gbuffer import GBuffer
from ..common.shading import Shading, load_shading
from .kernel_module import SPLIT_MODULE
from .params import DIParams
from .reservoir import DIReservoir, light_visible


@wp.func
def visible_reservoir(scene: SceneDevice, sh: Shading, r: DIReservoir):
    """The stage's work for one pixel: (the reservoir with W = 0 if its sample is occluded, events)."""
    out = r
    rays = int(0)
    if r.W > 0.0:
        rays = 1
        if not light_visible(scene, sh.hit, r):
            out.W = 0.0
    return out, ray_events(rays)


@wp.kernel(module=SPLIT_MODULE)
def visibility_kernel(offset: int, scene: SceneDevice, params: DIParams, gb: GBuffer,
                      reservoirs_in: wp.array(dtype=DIReservoir), reservoirs_out: wp.array(dtype=DIReservoir),
                      events: wp.array(dtype=EventCounts)):
    """The stage on its own (`stages.split`)."""
    pixel = wp.tid() + offset
    r, ev = visible_reservoir(scene, load_shading(scene, gb, pixel), reservoirs_in[pixel])
    reservoirs_out[pixel] = r
    events[pixel] = packed_events(ev)
