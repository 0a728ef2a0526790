"""Per-frame values of the ReSTIR DI stages (runtime, not compile-time)."""
import warp as wp


@wp.struct
class DIParams:
    seed: wp.uint32
    frame: wp.uint32
    sample: int          # sample index within the frame (spp > 1 repeats the pipeline)
    candidates: int      # initial light candidates per pixel (N_L)
    bsdf_candidates: int  # initial BSDF candidates per pixel (N_B)
    visibility: int      # 1: visibility-aware targets in reuse (after the visibility stage)
    hide_emitters: int
    temporal_cap: float  # previous confidence capped to temporal_cap * current M (<= 0: no cap)
    spatial_round: int   # index of the spatial round being run
    spatial_k: int       # configured neighbour count (enters the pairwise weights)
    spatial_radius: float  # neighbour search radius in pixels
