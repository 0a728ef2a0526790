"""Random streams: which stage owns which stream, and how each stage lays out its dimensions.

A random number is rng_uniform(rng_key(seed, frame, STAGE, pixel), dim) (device/rng.py). Two
uses of the same (stage, dim) would correlate decisions that the estimators assume independent,
so every stage id range and every per-sample dimension layout is declared here, once, and
`tests/unit/test_streams.py` checks that no two overlap (`STAGE_RANGES`, `DIM_LAYOUTS`).

A stage's dimensions for sample s (the spp index within a frame) start at s * DIMS_PER_SAMPLE of
that stage; within a sample each use has a named offset.
"""
import warp as wp

# ----------------------------------------------------------------------------- stage ids
STAGE_CAMERA = wp.constant(0)      # camera rays of every method (common random numbers)
STAGE_LENS = wp.constant(2)        # the thin lens's aperture samples (kept apart: pinhole images do not change)
STAGE_PATH_TRACE = wp.constant(1)  # the path tracer's paths (and its first light sample per vertex)
STAGE_DI_INITIAL = wp.constant(11)
STAGE_DI_SHADE = wp.constant(12)
STAGE_DI_TEMPORAL = wp.constant(13)
STAGE_DI_SPATIAL = wp.constant(20)  # + round index, round < MAX_SPATIAL_ROUNDS
STAGE_PT_PATHS = wp.constant(30)     # ReSTIR PT's base paths (keyed further by sample and candidate)
STAGE_PT_RIS = wp.constant(31)       # ReSTIR PT's streaming-RIS selections (never the paths' stream)
STAGE_PT_TEMPORAL = wp.constant(32)
STAGE_PT_MCMC = wp.constant(33)       # ReSTIR PT's MCMC suffix mutations (keyed further by sample and step)
STAGE_PT_SPATIAL = wp.constant(40)   # + round index, round < MAX_SPATIAL_ROUNDS
STAGE_SR_PREFIX = wp.constant(50)           # Suffix ReSTIR: the prefixes traced for temporal prefix reuse
STAGE_SR_PREFIX_TEMPORAL = wp.constant(51)  # its selections
STAGE_SR_SUFFIX = wp.constant(52)           # the suffixes traced at the resampled prefix ends (keyed as PT's base paths)
STAGE_SR_SUFFIX_RIS = wp.constant(53)       # their streaming-RIS selections
STAGE_SR_SUFFIX_TEMPORAL = wp.constant(54)
STAGE_SR_GATHER_PREFIX = wp.constant(55)    # the final gather's fresh prefixes (keyed by sample and prefix)
STAGE_SR_GATHER_SUFFIX = wp.constant(56)    # the final gather's canonical suffixes (keyed as its prefixes)
STAGE_SR_GATHER_RIS = wp.constant(57)       # its streaming-RIS selections
STAGE_SR_GATHER_FALLBACK = wp.constant(58)  # gather slots the search left empty: random screen neighbours
STAGE_SR_SUFFIX_SPATIAL = wp.constant(60)   # + round index, round < MAX_SPATIAL_ROUNDS
STAGE_PT_SPATIAL_PAIRING = wp.constant(70)  # + round index: ReSTIR PT's reciprocal pairings (one stream a frame)
STAGE_PATH_NEE = wp.constant(256)  # + j: the path tracer's j-th extra light sample per vertex (0 < j < 256)

MAX_SPATIAL_ROUNDS = 8
MAX_NEE_SAMPLES = 256

# (name, first stage id, number of consecutive ids)
STAGE_RANGES = (
    ("camera", STAGE_CAMERA, 1),
    ("lens", STAGE_LENS, 1),
    ("path_trace", STAGE_PATH_TRACE, 1),
    ("di_initial", STAGE_DI_INITIAL, 1),
    ("di_shade", STAGE_DI_SHADE, 1),
    ("di_temporal", STAGE_DI_TEMPORAL, 1),
    ("di_spatial", STAGE_DI_SPATIAL, MAX_SPATIAL_ROUNDS),
    ("pt_paths", STAGE_PT_PATHS, 1),
    ("pt_ris", STAGE_PT_RIS, 1),
    ("pt_temporal", STAGE_PT_TEMPORAL, 1),
    ("pt_mcmc", STAGE_PT_MCMC, 1),
    ("pt_spatial", STAGE_PT_SPATIAL, MAX_SPATIAL_ROUNDS),
    ("sr_prefix", STAGE_SR_PREFIX, 1),
    ("sr_prefix_temporal", STAGE_SR_PREFIX_TEMPORAL, 1),
    ("sr_suffix", STAGE_SR_SUFFIX, 1),
    ("sr_suffix_ris", STAGE_SR_SUFFIX_RIS, 1),
    ("sr_suffix_temporal", STAGE_SR_SUFFIX_TEMPORAL, 1),
    ("sr_gather_prefix", STAGE_SR_GATHER_PREFIX, 1),
    ("sr_gather_suffix", STAGE_SR_GATHER_SUFFIX, 1),
    ("sr_gather_ris", STAGE_SR_GATHER_RIS, 1),
    ("sr_gather_fallback", STAGE_SR_GATHER_FALLBACK, 1),
    ("sr_suffix_spatial", STAGE_SR_SUFFIX_SPATIAL, MAX_SPATIAL_ROUNDS),
    ("pt_spatial_pairing", STAGE_PT_SPATIAL_PAIRING, MAX_SPATIAL_ROUNDS),
    ("path_nee", STAGE_PATH_NEE + 1, MAX_NEE_SAMPLES - 1),
)

# ----------------------------------------------------------------------------- camera
CAMERA_DIMS_PER_SAMPLE = wp.constant(2)   # the filter-importance-sampled pixel position

# ----------------------------------------------------------------------------- path tracer
# DIMS_PER_BOUNCE numbers per bounce; bounce b (b >= 1: the vertex after b-1 scatters) starts at
# s * DIMS_PER_SAMPLE + b * DIMS_PER_BOUNCE. Slot 0 is free (camera rays have their own stream);
# the extra light samples' streams (STAGE_PATH_NEE + j) use the same layout. (Russian roulette
# once drew slot 7, the BSDF direction's second number: survival then depended on the sampled
# direction, a bias with `rr=true` that test_streams.py found.)
DIMS_PER_BOUNCE = wp.constant(8)
DIMS_PER_SAMPLE = wp.constant(8 * 1024)
MAX_SEGMENTS = 1023                # DIMS_PER_SAMPLE / DIMS_PER_BOUNCE - 1: samples never overlap
DIM_LIGHT_SELECT = wp.constant(2)  # 1 number
DIM_LIGHT_POINT = wp.constant(3)   # 2 numbers
DIM_BSDF_LOBE = wp.constant(5)     # 1 number
DIM_BSDF_DIR = wp.constant(6)      # 2 numbers
DIM_RR = wp.constant(1)            # 1 number: Russian roulette

# ----------------------------------------------------------------------------- ReSTIR DI
# initial RIS: candidate j uses s * DIMS_PER_SAMPLE + j * DI_DIMS_PER_CANDIDATE + {0: light or lobe
# selection, 1-2: point on the light or BSDF direction, 3: the RIS selection}
DI_DIMS_PER_CANDIDATE = wp.constant(4)
DI_DIM_CANDIDATE_SELECT = wp.constant(0)
DI_DIM_CANDIDATE_POINT = wp.constant(1)
DI_DIM_CANDIDATE_RIS = wp.constant(3)
DI_MAX_CANDIDATES = 2048           # DIMS_PER_SAMPLE / DI_DIMS_PER_CANDIDATE
# shading: s * DIMS_PER_SAMPLE + {0: lobe, 1-2: direction} of the delta-lobe BSDF sample
DI_DIM_SHADE_LOBE = wp.constant(0)
DI_DIM_SHADE_DIR = wp.constant(1)
# temporal: s * DI_TEMPORAL_DIMS_PER_SAMPLE + {0: the current input's selection, 1: the history's}
DI_TEMPORAL_DIMS_PER_SAMPLE = wp.constant(4)
# spatial (one stream per round): neighbour j uses s * DI_SPATIAL_DIMS_PER_SAMPLE +
# j * DI_SPATIAL_DIMS_PER_NEIGHBOR + {0-1: disk offset, 2: selection}; the canonical input's
# selection is DI_SPATIAL_DIM_CANONICAL
DI_SPATIAL_DIMS_PER_SAMPLE = wp.constant(256)
DI_SPATIAL_DIMS_PER_NEIGHBOR = wp.constant(4)
DI_SPATIAL_DIM_OFFSET = wp.constant(0)
DI_SPATIAL_DIM_SELECT = wp.constant(2)
DI_SPATIAL_DIM_CANONICAL = wp.constant(255)
# reciprocal spatial reuse (ReSTIR PT's spatial.reciprocal): neighbour j's pairing is drawn once a
# frame from the pairing stream (pixel 0) at s * DI_SPATIAL_DIMS_PER_SAMPLE + j *
# DI_SPATIAL_DIMS_PER_NEIGHBOR + {0-1: the XOR mask, 2-3: the grid's shift}; in each pixel's own
# stream the pair's selection is DI_SPATIAL_DIM_SELECT and the canonical input's share of the pair
# DI_SPATIAL_DIM_SHARE (the disk offset's dimensions are not drawn in this mode)
PAIRING_DIM_MASK = wp.constant(0)
PAIRING_DIM_SHIFT = wp.constant(2)
DI_SPATIAL_DIM_SHARE = wp.constant(3)
DI_MAX_NEIGHBORS = 32

# ----------------------------------------------------------------------------- ReSTIR PT
# Base paths: one key per (pixel, sample, candidate) path (rng_key of STAGE_PT_PATHS combined with
# sample * candidates + candidate), stored in the reservoir as the path's replay seed; bounce b
# uses the path tracer's layout at b * DIMS_PER_BOUNCE. Replay re-reads the same (key, dim) pairs,
# so it consumes exactly the numbers the base path did, whatever it skips
# (docs/theory/restir_pt.md#random-replay).
# RIS selections: the same per-path key in STAGE_PT_RIS, dimension 2 * (vertex index) + {0: the
# NEE event there, 1: the BSDF-sampled emission found from there}.
PT_RIS_DIMS_PER_VERTEX = wp.constant(2)
PT_RIS_DIM_NEE = wp.constant(0)
PT_RIS_DIM_EMISSION = wp.constant(1)
PT_MAX_CANDIDATES = 64
# temporal: s * PT_TEMPORAL_DIMS_PER_SAMPLE + {0: the current input's selection, 1: the history's}
PT_TEMPORAL_DIMS_PER_SAMPLE = wp.constant(4)
# spatial: as ReSTIR DI's (one stream per round)
PT_MAX_NEIGHBORS = DI_MAX_NEIGHBORS
# MCMC suffix mutations: one key per (pixel, sample, step) (rng_key of STAGE_PT_MCMC combined with
# sample * PT_MAX_MCMC_STEPS + step); the proposed suffix draws the base paths' per-bounce layout
# from the rc vertex on, and the acceptance number is dimension PT_MCMC_DIM_ACCEPT, below every
# bounce's numbers
PT_MAX_MCMC_STEPS = 8
PT_MCMC_DIM_ACCEPT = wp.constant(0)

# ----------------------------------------------------------------------------- Suffix ReSTIR
# Prefixes and suffixes are keyed per path as ReSTIR PT's base paths (their bounce layout, the
# suffix's counted from the prefix end); the gather's fresh prefix i of sample s, and the
# canonical suffix traced from its end, are path s * SR_MAX_GATHER_PREFIXES + i. Prefix temporal reuse: s * SR_PREFIX_TEMPORAL_DIMS_PER_SAMPLE +
# {0: the current prefix's selection, 1: the history's}; suffix temporal and spatial reuse: as
# ReSTIR PT's. Gather fallback: slot m of prefix i of sample s uses
# (s * SR_MAX_GATHER_PREFIXES + i) * SR_FALLBACK_DIMS_PER_PREFIX + 2 m + {0, 1} (the disk offset).
SR_MAX_GATHER_PREFIXES = wp.constant(128)  # the paper's largest N (16 before: renders at spp > 1 drew other numbers)
SR_PREFIX_TEMPORAL_DIMS_PER_SAMPLE = wp.constant(4)
SR_FALLBACK_DIMS_PER_PREFIX = wp.constant(16)
SR_MAX_GATHER_SUFFIXES = 8

# (stage, numbers per sample, [(first, count) of each use within one sample at the largest settings])
DIM_LAYOUTS = (
    ("camera", CAMERA_DIMS_PER_SAMPLE, [(0, 2)]),
    ("path_trace", DIMS_PER_SAMPLE,
     [(b * DIMS_PER_BOUNCE + o, n) for b in range(1, MAX_SEGMENTS + 1)
      for o, n in ((DIM_LIGHT_SELECT, 1), (DIM_LIGHT_POINT, 2), (DIM_BSDF_LOBE, 1), (DIM_BSDF_DIR, 2), (DIM_RR, 1))]),
    ("di_initial", DIMS_PER_SAMPLE,
     [(j * DI_DIMS_PER_CANDIDATE + o, n) for j in range(DI_MAX_CANDIDATES)
      for o, n in ((DI_DIM_CANDIDATE_SELECT, 1), (DI_DIM_CANDIDATE_POINT, 2), (DI_DIM_CANDIDATE_RIS, 1))]),
    ("di_shade", DIMS_PER_SAMPLE, [(DI_DIM_SHADE_LOBE, 1), (DI_DIM_SHADE_DIR, 2)]),
    ("di_temporal", DI_TEMPORAL_DIMS_PER_SAMPLE, [(0, 1), (1, 1)]),
    ("di_spatial", DI_SPATIAL_DIMS_PER_SAMPLE,
     [(j * DI_SPATIAL_DIMS_PER_NEIGHBOR + o, n) for j in range(DI_MAX_NEIGHBORS)
      for o, n in ((DI_SPATIAL_DIM_OFFSET, 2), (DI_SPATIAL_DIM_SELECT, 1))] + [(DI_SPATIAL_DIM_CANONICAL, 1)]),
    ("pt_paths", DIMS_PER_SAMPLE,
     [(b * DIMS_PER_BOUNCE + o, n) for b in range(1, MAX_SEGMENTS + 1)
      for o, n in ((DIM_LIGHT_SELECT, 1), (DIM_LIGHT_POINT, 2), (DIM_BSDF_LOBE, 1), (DIM_BSDF_DIR, 2))]),
    ("pt_ris", DIMS_PER_SAMPLE,
     [(v * PT_RIS_DIMS_PER_VERTEX + o, 1) for v in range(MAX_SEGMENTS) for o in (PT_RIS_DIM_NEE, PT_RIS_DIM_EMISSION)]),
    ("pt_temporal", PT_TEMPORAL_DIMS_PER_SAMPLE, [(0, 1), (1, 1)]),
    ("pt_mcmc", DIMS_PER_SAMPLE,
     [(PT_MCMC_DIM_ACCEPT, 1)] + [(b * DIMS_PER_BOUNCE + o, n) for b in range(1, MAX_SEGMENTS + 1)
                                  for o, n in ((DIM_LIGHT_SELECT, 1), (DIM_LIGHT_POINT, 2), (DIM_BSDF_LOBE, 1),
                                               (DIM_BSDF_DIR, 2))]),
    ("pt_spatial", DI_SPATIAL_DIMS_PER_SAMPLE,
     [(j * DI_SPATIAL_DIMS_PER_NEIGHBOR + o, n) for j in range(PT_MAX_NEIGHBORS)
      for o, n in ((DI_SPATIAL_DIM_OFFSET, 2), (DI_SPATIAL_DIM_SELECT, 1), (DI_SPATIAL_DIM_SHARE, 1))]
     + [(DI_SPATIAL_DIM_CANONICAL, 1)]),
    ("pt_spatial_pairing", DI_SPATIAL_DIMS_PER_SAMPLE,
     [(j * DI_SPATIAL_DIMS_PER_NEIGHBOR + o, 2) for j in range(PT_MAX_NEIGHBORS)
      for o in (PAIRING_DIM_MASK, PAIRING_DIM_SHIFT)]),
    ("sr_prefix_temporal", SR_PREFIX_TEMPORAL_DIMS_PER_SAMPLE, [(0, 1), (1, 1)]),
    ("sr_gather_fallback", SR_MAX_GATHER_PREFIXES * SR_FALLBACK_DIMS_PER_PREFIX,
     [(i * SR_FALLBACK_DIMS_PER_PREFIX + 2 * m, 2) for i in range(SR_MAX_GATHER_PREFIXES)
      for m in range(SR_MAX_GATHER_SUFFIXES)]),
)
