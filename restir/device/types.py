"""Named tags shared by host and device code (never bare integers in kernels)."""
import warp as wp

# Material kinds (one per Mitsuba BSDF plugin we support; `twosided` is a flag, not a kind).
MAT_DIFFUSE = wp.constant(0)
MAT_CONDUCTOR = wp.constant(1)
MAT_ROUGHCONDUCTOR = wp.constant(2)
MAT_DIELECTRIC = wp.constant(3)
MAT_THINDIELECTRIC = wp.constant(4)
MAT_ROUGHDIELECTRIC = wp.constant(5)
MAT_PLASTIC = wp.constant(6)
MAT_ROUGHPLASTIC = wp.constant(7)

# Microfacet distributions.
MICROFACET_BECKMANN = wp.constant(0)
MICROFACET_GGX = wp.constant(1)

# Reconstruction filters (sampled by filter importance sampling).
FILTER_BOX = wp.constant(0)
FILTER_TENT = wp.constant(1)
FILTER_GAUSSIAN = wp.constant(2)

# Environment emitter kinds.
ENV_NONE = wp.constant(0)
ENV_CONSTANT = wp.constant(1)
ENV_MAP = wp.constant(2)

# Path-tracer estimator strategies (the three must agree in expectation).
STRATEGY_MIS = wp.constant(0)
STRATEGY_NEE = wp.constant(1)
STRATEGY_BSDF = wp.constant(2)

# Random-stream stage ids: no two stages share a stream.
STAGE_CAMERA = wp.constant(0)      # camera rays of every method (common random numbers)
STAGE_PATH_TRACE = wp.constant(1)
STAGE_PATH_NEE = wp.constant(256)  # + j: the path tracer's j-th extra light sample per vertex (j < 256)
STAGE_DI_INITIAL = wp.constant(11)
STAGE_DI_SHADE = wp.constant(12)
STAGE_DI_TEMPORAL = wp.constant(13)
STAGE_DI_SPATIAL = wp.constant(20)  # + round index

# Random dimensions within one sample: DIMS_PER_BOUNCE numbers per bounce.
DIMS_PER_BOUNCE = wp.constant(8)
DIMS_PER_SAMPLE = wp.constant(8 * 1024)
# Offsets of each use inside a bounce (slots 0 and 1 are free: camera rays use STAGE_CAMERA).
DIM_LIGHT_SELECT = wp.constant(2)  # 1 number
DIM_LIGHT_POINT = wp.constant(3)   # 2 numbers
DIM_BSDF_LOBE = wp.constant(5)     # 1 number
DIM_BSDF_DIR = wp.constant(6)      # 2 numbers

PI = wp.constant(3.14159265358979323846)
INV_PI = wp.constant(0.31830988618379067154)
INV_TWO_PI = wp.constant(0.15915494309189533577)
INV_FOUR_PI = wp.constant(0.07957747154594766788)
