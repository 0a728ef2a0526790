"""Per-frame values of the path-reuse stages (runtime, not compile-time): ReSTIR PT's, and each
suffix domain's in Suffix ReSTIR; and the shift kinds."""
import warp as wp

SHIFT_HYBRID = wp.constant(0)        # replay up to the first vertex that qualifies, then reconnect
SHIFT_RECONNECTION = wp.constant(1)  # always reconnect at x2 (length 1), no conditions
SHIFT_REPLAY = wp.constant(2)        # replay the whole path with the source's random numbers
SHIFTS = {"hybrid": SHIFT_HYBRID, "reconnection": SHIFT_RECONNECTION, "replay": SHIFT_REPLAY}



@wp.struct
class PathReuseParams:
    seed: wp.uint32
    frame: wp.uint32
    sample: int            # sample index within the frame (spp > 1 repeats the pipeline)
    candidates: int        # base paths per pixel (each is one streaming-RIS reservoir of M = 1)
    max_depth: int         # Mitsuba's meaning: path segments, the camera segment included
    first_event: int       # the first vertex index whose events are resampled: 0 with direct=pt, else 1
    direct_nee: int        # 1 (direct=nee): the events at x_0 (NEE, emission found from x_0) summed, not resampled
    expected_out: int      # 1: this pass is the last and writes its expected output (ReSTIR PT's shade.expected)
    shift: int             # SHIFT_*
    near_distance: float   # hybrid: the shortest reconnection segment (scene units; official 0.1)
    rough_threshold: float  # hybrid: glossy lobes rougher than this linear roughness are rough (official 0.2)
    temporal_cap: float    # history confidence capped to temporal_cap x the current one (<= 0: no cap)
    spatial_round: int
    spatial_k: int         # configured neighbour count (enters the pairwise weights)
    spatial_radius: float  # neighbour disk radius in pixels
