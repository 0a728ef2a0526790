"""Per-pixel event counts that every stage writes and the stage runner sums into counters.

A stage counts in a vec4i: [non-finite resampling weights or outputs, zero-weight resampling
inputs, failed shifts, rays traced]. A shift "fails" when a reused sample with W > 0 has target 0
in the destination domain (it lands outside the destination's support). Counted, never hidden.

The per-pixel scratch the counts are written to is packed to 8 bytes (`EventCounts`, to save
memory): the rays in 32 bits, the three rare counts in 10 bits each. A pass's other per-pixel
counts (shifts tried and succeeded, samples by origin, gather slots) are four 16-bit counts
(`PassCounts`). Both saturate instead of wrapping, and the tally counts every saturated field,
so a count that did not fit is reported as a lower bound, never silently wrong (a pixel meets
1023 non-finite weights in one stage only with more than 1023 candidates).
"""
import warp as wp

from ...resampling.ris import RisState

EV_NONFINITE = wp.constant(0)
EV_ZERO_WEIGHT = wp.constant(1)
EV_FAILED_SHIFT = wp.constant(2)
EV_RAYS = wp.constant(3)
EV_SATURATED = 4  # the tally's fifth sum: fields that saturated
COUNTER_NAMES = ("nonfinite", "zero_weight_inputs", "failed_shifts")

EventCounts = wp.vec2ui  # (rays, the three counts in bits 0-9, 10-19, 20-29)
PassCounts = wp.vec4us
COUNT_BITS = wp.constant(10)
COUNT_MAX = wp.constant(1023)          # a packed event count's largest value
PASS_COUNT_MAX = wp.constant(65535)    # a pass count's


@wp.func
def packed_events(e: wp.vec4i) -> EventCounts:
    """A stage's counts as the pixel's 8 bytes of event scratch (counts above the fields' range
    saturate; the tally reports them)."""
    c = wp.uint32(0)
    for i in range(3):
        c = c | (wp.uint32(wp.clamp(e[i], 0, COUNT_MAX)) << wp.uint32(COUNT_BITS * i))
    return EventCounts(wp.uint32(wp.max(e[3], 0)), c)


@wp.func
def packed_counts(n: wp.vec4i) -> PassCounts:
    """A pass's four per-pixel counts in 16 bits each (saturating; the tally reports it)."""
    return PassCounts(wp.uint16(wp.clamp(n[0], 0, PASS_COUNT_MAX)), wp.uint16(wp.clamp(n[1], 0, PASS_COUNT_MAX)),
                      wp.uint16(wp.clamp(n[2], 0, PASS_COUNT_MAX)), wp.uint16(wp.clamp(n[3], 0, PASS_COUNT_MAX)))


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
