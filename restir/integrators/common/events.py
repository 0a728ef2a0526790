"""Per-pixel event counts that every stage writes and the stage runner sums into counters.

A vec4i per pixel: [non-finite resampling weights or outputs, zero-weight resampling inputs,
failed shifts, rays traced]. A shift "fails" when a reused sample with W > 0 has target 0 in the
destination domain (it lands outside the destination's support). Counted, never hidden.
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


@wp.func
def ray_events(rays: int) -> wp.vec4i:
    return wp.vec4i(0, 0, 0, rays)


@wp.func
def output_events(L: wp.vec3, rays: int) -> wp.vec4i:
    """Events of a stage that writes a pixel's radiance: a NaN or inf output is counted."""
    finite = L[0] == L[0] and L[1] == L[1] and L[2] == L[2] and wp.abs(L[0] + L[1] + L[2]) < 3.0e38
    return wp.vec4i(wp.where(finite, 0, 1), 0, 0, rays)
