"""Per-pixel event counts that each ReSTIR DI stage writes and the pipeline sums into counters.

A vec4i per pixel: [non-finite resampling weights or outputs, zero-weight resampling inputs,
failed shifts, rays traced]. A shift "fails" here when a reused sample with W > 0 has target 0
in the destination domain (DI's identity shift lands outside the destination's support: behind
the surface, outside the lobe, or occluded with visibility-aware targets). Counted, never hidden.
"""
import warp as wp

from ...resampling.ris import RisState

EV_NONFINITE = wp.constant(0)
EV_ZERO_WEIGHT = wp.constant(1)
EV_FAILED_SHIFT = wp.constant(2)
EV_RAYS = wp.constant(3)
COUNTER_NAMES = ("nonfinite", "zero_weight_inputs", "failed_shifts")


@wp.func
def stage_events(s: RisState, failed_shifts: int, rays: int) -> wp.vec4i:
    return wp.vec4i(s.nonfinite, s.zero, failed_shifts, rays)
