"""The stored ReSTIR PT path sample (a reservoir) and its flags.

A path sample is the random numbers of one base path (its replay seed: every number the path
drew is rng_uniform(seed, dim) at a fixed dimension) together with which of its events was
chosen: path length (the last scattering vertex; vertex index 0 is the primary hit x1) and end
type (a light-sampled connection, NEE, or emission found by BSDF sampling). Its integrand in
its own domain is F = f / p in primary sample space, the NEE/BSDF MIS weight included; the
target is p_hat = luminance(F) (docs/theory/restir_pt.md#primary-sample-space).

For the reconnection shift it also keeps the reconnection (rc) vertex z, which every shifted
path shares, with what the path does after it, and the source-side terms of the Jacobian:

| field     | bytes | meaning |
|-----------|-------|---------|
| F         | 12    | integrand of the selected path in the domain that stores it |
| W, M      | 4 + 4 | unbiased contribution weight, confidence |
| flags     | 4     | path length, rc length, lobes at rcPrev and at z, end type, rc kind, delta light |
| seed      | 4     | the base path's random-number key (replay) |
| rc_tri    | 4     | z's triangle (a surface or an emissive triangle); -1 for an environment rc |
| rc_bary   | 8     | z's barycentrics (full floats: z is rebuilt exactly) |
| rc_wi     | 12    | direction leaving z (BSDF sample, NEE light, or the environment direction) |
| rc_L      | 12    | radiance cached at z (see below) |
| rc_jac    | 8     | source terms of J: (G(rcPrev, z) * p(rcPrev -> z), p(z -> next)), the latter 1 where it does not apply |
| light_pdf | 4     | light pdf of the path's end, in the measure the shift needs (below) |

Total 76 bytes (the official implementation's is 88; docs/theory/restir_pt.md#what-a-path-sample-stores).
`rc_L` by case: NEE at z: Le of the
light (its MIS weight is recomputed after a shift, so it is not in rc_L; a delta light's is 1, and
the flags say which it is); emission found from z:
Le; a path continuing past z: the product of what follows z's own scatter (MIS weight
included); z the emitter itself (an "escape" rc vertex): unused (Le is re-read from the
triangle). `light_pdf`: the solid-angle light pdf at z when the end's MIS is taken at z (z does
not move, so it is fixed); the area-measure pdf of the emitter when z is that emitter, converted
with the destination's geometry after a shift; the environment's pdf of rc_wi for
an environment rc (fixed direction).
"""
import warp as wp

from ...resampling.ris import ReservoirWeights

# flags: bits 0-7 path length, 8-15 rc length (NO_RC: none), 16-18 lobe at rcPrev, 19-21 lobe at z
# (lobe codes: 0 none or all lobes, else 1 + the LOBE_* bit), bit 22 NEE end, bits 23-24 rc kind,
# bits 25-26 origin (which input of the last reuse passes the sample came from; for the stats),
# bit 27 the NEE end's light is a delta light
NO_RC = wp.constant(255)
PATH_NONE = wp.constant(-1)      # flags of a reservoir that holds no path
RC_SURFACE = wp.constant(0)      # z is a scattering vertex
RC_EMITTER = wp.constant(1)      # z is the emitter the path ends on (escape vertex)
RC_ENV = wp.constant(2)          # z is the environment, in direction rc_wi
ORIGIN_CANONICAL = wp.constant(0)  # this frame's own base path
ORIGIN_TEMPORAL = wp.constant(1)   # selected from the previous frame by temporal reuse
ORIGIN_SPATIAL = wp.constant(2)    # selected from a neighbour by spatial reuse
MAX_PATH_LENGTH = 254            # the 8-bit length fields


@wp.struct
class PathReservoir:
    F: wp.vec3
    W: float
    M: float
    flags: int
    seed: wp.uint32
    rc_tri: int
    rc_bary: wp.vec2
    rc_wi: wp.vec3
    rc_L: wp.vec3
    rc_jac: wp.vec2
    light_pdf: float


@wp.func
def lobe_code(lobe: int) -> int:
    """A LOBE_* flag (one bit of seven) as a 3-bit code: 0 for none, else 1 + the bit's index."""
    code = int(0)
    for b in range(7):
        if lobe == (1 << b):
            code = b + 1
    return code


@wp.func
def lobe_from_code(code: int) -> int:
    if code == 0:
        return 0
    return 1 << (code - 1)


@wp.func
def pack_flags(path_length: int, rc_length: int, lobe_prev: int, lobe_rc: int, nee: int, rc_kind: int) -> int:
    return path_length | (rc_length << 8) | (lobe_code(lobe_prev) << 16) | (lobe_code(lobe_rc) << 19) | (
        nee << 22) | (rc_kind << 23)


@wp.func
def path_length(flags: int) -> int:
    return flags & 255


@wp.func
def rc_length(flags: int) -> int:
    return (flags >> 8) & 255


@wp.func
def lobe_at_rc_prev(flags: int) -> int:
    return lobe_from_code((flags >> 16) & 7)


@wp.func
def lobe_at_rc(flags: int) -> int:
    return lobe_from_code((flags >> 19) & 7)


@wp.func
def with_lobe_at_rc(flags: int, lobe: int) -> int:
    """flags with the lobe at z replaced (an MCMC mutation samples z's lobe afresh)."""
    return (flags & ~(7 << 19)) | (lobe_code(lobe) << 19)


@wp.func
def with_lobe_at_rc_prev(flags: int, lobe: int) -> int:
    """flags with the lobe at rcPrev replaced (a mutation that moves z samples it afresh)."""
    return (flags & ~(7 << 16)) | (lobe_code(lobe) << 16)


@wp.func
def ends_with_nee(flags: int) -> int:
    return (flags >> 22) & 1


@wp.func
def ends_on_delta_light(flags: int) -> int:
    """The path's NEE end connects to a delta light (no BSDF technique: MIS weight 1)."""
    return (flags >> 27) & 1


@wp.func
def with_delta_light(flags: int, delta: int) -> int:
    """flags with the NEE end's light kind set (delta: 1 for a delta light)."""
    return (flags & ~(1 << 27)) | (delta << 27)


@wp.func
def rc_kind(flags: int) -> int:
    return (flags >> 23) & 3


@wp.func
def origin(flags: int) -> int:
    return (flags >> 25) & 3


@wp.func
def with_origin(r: PathReservoir, origin: int) -> PathReservoir:
    out = r
    if out.flags != PATH_NONE:
        out.flags = (out.flags & ~(3 << 25)) | (origin << 25)
    return out


@wp.func
def empty_path() -> PathReservoir:
    r = PathReservoir()
    r.flags = PATH_NONE
    r.rc_tri = -1
    r.W = 0.0
    r.M = 0.0
    return r


@wp.func
def holds_path(r: PathReservoir) -> bool:
    return r.flags != PATH_NONE


@wp.func
def sample_output(r: PathReservoir) -> wp.vec3:
    """The reservoir's estimate of its pixel's paths, F(Y) W (before the filter weight): what the
    shade stage adds; 0 without a path."""
    if holds_path(r) and r.W > 0.0:
        return r.F * r.W
    return wp.vec3(0.0)


@wp.func
def store(chosen: PathReservoir, f: ReservoirWeights) -> PathReservoir:
    """The stored result of a resampling pass: the chosen input's path (already shifted into this
    domain: F and rc_jac are this domain's) with the pass's W and M; with nothing selected, no
    path but the confidence. The one field copy of every PT stage."""
    r = chosen
    r.W = f.W
    r.M = f.M
    if f.selected == 0:
        r.flags = PATH_NONE
        r.F = wp.vec3(0.0)
    return r
