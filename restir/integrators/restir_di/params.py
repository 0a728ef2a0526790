"""Per-frame values of the ReSTIR DI stages (runtime, not compile-time)."""
import warp as wp


@wp.struct
class DIParams:
    seed: wp.uint32
    frame: wp.uint32
    sample: int          # sample index within the frame (spp > 1 repeats the pipeline)
    candidates: int      # initial light candidates per pixel
    hide_emitters: int
