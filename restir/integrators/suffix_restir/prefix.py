"""Prefixes (docs/theory/suffix_restir.md#the-prefix-end and #prefix-resampling;
docs/guide/suffix_restir.md): the adaptive prefix-end rule, a prefix traced with its internal
events, the prefix reservoir, and the prefix's shift to another pixel (temporal prefix reuse).

Vertex 0 is the primary hit. A prefix ends at x_P, one vertex after the first bounce that samples
a rough lobe, unless x_P is specular-only or reached over a segment of at most `short_segment`
(then the search goes on), with P >= min_prefix and P + 2 <= max_depth (`prefix_ends_at`; with
prefix.adaptive=false, exactly at P = min_prefix). The prefix's events of
length < P (NEE at x_k, emission found from x_k; from the first event on) are its internal
contributions, summed as the path tracer sums them. A path without a prefix end is all internal.
Prefix numbers are rng_uniform(seed, bounce_dim(k, slot)) at bounce k, as a ReSTIR PT base path's.
"""
import warp as wp

from ...device.bounce import found_along, material_at, nee_at, scatter_at, segment, shading_frame
from ...device.bsdf import Material, bsdf_has_rough_component, bsdf_is_delta_only, bsdf_pdf_lobes, lobe_is_rough
from ...device.color import luminance, max3
from ...device.intersect import T_MAX, SurfaceHit, trace_closest, visible_to_light
from ...device.path_steps import emission_mis_weight
from ...device.sampling import to_local
from ...device.scene_device import SceneDevice
from ...device.types import STRATEGY_MIS
from ...resampling.ris import is_finite
from ..common.shading import Shading
from ..path_reuse.path_sample import lobe_code, lobe_from_code
from ..path_reuse.rc_criteria import eval_lobe, lobe_weight
from .params import SRParams


@wp.func
def prefix_ends_at(params: SRParams, k: int, rough_bounce: bool, mat: Material, dist: float) -> bool:
    """x_k, reached from x_{k-1} over a segment of length dist by a lobe that was rough_bounce, ends
    the prefix (docs/theory/suffix_restir.md#the-prefix-end). Adaptive: the first rough bounce at or
    after min_prefix, unless x_k is specular-only or the segment short (each rejection can be
    switched off); otherwise exactly at min_prefix."""
    if k + 2 > params.pt.max_depth:
        return False
    if params.adaptive == 0:
        return k == params.min_prefix
    if k < params.min_prefix or not rough_bounce:
        return False
    if params.avoid_specular_end != 0 and not bsdf_has_rough_component(mat, params.pt.rough_threshold):
        return False
    return params.avoid_short_end == 0 or dist > params.short_segment


@wp.struct
class Prefix:
    valid: int         # the path has a prefix end
    length: int        # P, the vertex index of x_P
    hit: SurfaceHit    # x_P
    dir: wp.vec3       # world direction of the segment x_{P-1} -> x_P
    dist: float        # its length (from x_{P-1}'s ray origin)
    thp: wp.vec3       # PSS throughput: the lobe weights of bounces 0..P-1
    jac: float         # G(x_{P-1}, x_P) p_l(x_{P-1} -> x_P): the source terms of a prefix shift's J
    lobe: int          # the lobe sampled at x_{P-1}
    footprint: float   # path length camera -> x_0 -> ... -> x_P (the search box's scale)
    internal: wp.vec3  # the prefix-internal events' contributions (the whole path's if no end)
    rays: int


# Inlined at its two calls (the prefix stage, the gather's fresh prefixes): out of line, each call
# copied the scene (1152 B), the parameters and the shading point, 4 times a pixel in the gather;
# inlined the frame is 4% cheaper, the CUDA build no slower
# (docs/changelog.md#speed-functions-that-copied-the-scene-inlined).
@wp.func(inline=True)
def trace_prefix(scene: SceneDevice, params: SRParams, x0: Shading, seed: wp.uint32, with_internal: bool) -> Prefix:
    """Trace from the primary hit x0 with the key `seed` until the prefix end (or the path's end);
    with_internal: also sum its internal events (the gather's prefixes). The prefix stage's fresh
    prefix goes without them (only its end and throughput are resampled; its light was a shadow
    ray a pixel, thrown away): the bounces' numbers are their own dimensions, so the path is the
    same either way."""
    out = Prefix()
    hit = x0.hit
    mat = x0.mat
    frame = x0.frame
    wi = x0.wi
    beta = wp.vec3(1.0)
    out.footprint = x0.hit.t
    k = int(0)
    while k + 2 <= params.pt.max_depth:
        if with_internal and k >= params.pt.first_event and bsdf_is_delta_only(mat) == 0:
            c = nee_at(scene, hit, mat, frame, wi, seed, wp.uint32(0), k, 1, STRATEGY_MIS)
            out.rays += c.rays
            out.internal += wp.cw_mul(beta, c.L)
        sc = scatter_at(hit, mat, frame, wi, seed, wp.uint32(0), k)
        if sc.valid == 0:
            break
        rough = lobe_is_rough(mat, sc.bs.lobe, params.pt.rough_threshold)
        beta = wp.cw_mul(beta, lobe_weight(mat, wi, sc.bs))
        if max3(beta) <= 0.0:
            break
        nh = trace_closest(scene, sc.o, sc.d, T_MAX)
        out.rays += 1
        fd = found_along(scene, hit, nh, sc.d)
        if with_internal and k >= params.pt.first_event and max3(fd.Le) > 0.0:  # emission from x_k: length k < P
            out.internal += wp.cw_mul(beta, fd.Le) * emission_mis_weight(sc.bs.is_delta, sc.bs.pdf, fd.p_light, 1,
                                                                         STRATEGY_MIS)
        if fd.is_env != 0:
            break
        frame_next = shading_frame(scene, nh, -sc.d)
        mat_next = material_at(scene, nh, frame_next)
        out.footprint += fd.dist
        if prefix_ends_at(params, k + 1, rough, mat_next, fd.dist):
            out.valid = 1
            out.length = k + 1
            out.hit = nh
            out.dir = fd.dir
            out.dist = fd.dist
            out.thp = beta
            out.lobe = sc.bs.lobe
            # as a shift recomputes them: from the segment between the two vertices
            out.jac = wp.abs(wp.dot(nh.ng, fd.dir)) / (fd.dist * fd.dist) * bsdf_pdf_lobes(
                mat, wi, to_local(frame, fd.dir), sc.bs.lobe)
            return out
        hit = nh
        mat = mat_next
        frame = frame_next
        wi = to_local(frame, -sc.d)
        k += 1
    return out


@wp.func
def prefix_end_shading(scene: SceneDevice, p: Prefix) -> Shading:
    """The suffix domain of a traced prefix: x_P with the direction back toward x_{P-1}."""
    s = Shading()
    s.valid = p.valid
    if p.valid != 0:
        s.hit = p.hit
        s.frame = shading_frame(scene, p.hit, -p.dir)
        s.mat = material_at(scene, p.hit, s.frame)
        s.wi = to_local(s.frame, -p.dir)
    return s


# ----------------------------------------------------------------------------- the prefix reservoir
@wp.struct
class PrefixReservoir:
    """A pixel's resampled prefix, its end x_P and direction stored in the prefix G-buffer.

    | field     | bytes | meaning |
    | W, M      | 4 + 4 | unbiased contribution weight (PSS), confidence |
    | p_hat     | 4     | luminance of the prefix throughput in this pixel's domain |
    | jac       | 4     | G(x_{P-1}, x_P) p_l(x_{P-1} -> x_P) of the path in this pixel's domain |
    | footprint | 4     | path length camera -> x_P (the search box's scale) |
    | seed      | 4     | the prefix's random-number key (replay of bounces 0..P-2) |
    | flags     | 4     | P (bits 0-7), lobe code at x_{P-1} (bits 8-10); -1: no prefix end |
    28 bytes."""
    W: float
    M: float
    p_hat: float
    jac: float
    footprint: float
    seed: wp.uint32
    flags: int


NO_PREFIX = wp.constant(-1)


@wp.func
def prefix_flags(length: int, lobe: int) -> int:
    return length | (lobe_code(lobe) << 8)


@wp.func
def prefix_length(flags: int) -> int:
    return flags & 255


@wp.func
def prefix_lobe(flags: int) -> int:
    return lobe_from_code((flags >> 8) & 7)


@wp.func
def has_prefix(r: PrefixReservoir) -> bool:
    return r.flags != NO_PREFIX


# ----------------------------------------------------------------------------- the prefix shift
@wp.struct
class PrefixShift:
    """A prefix moved to another primary hit: its throughput there (p_hat = luminance), J, and
    the new last segment (direction into x_P, length, G p_l for the record, footprint)."""
    valid: int
    thp: wp.vec3
    J: float
    dir: wp.vec3
    dist: float
    jac: float
    footprint: float
    rays: int


@wp.func(inline=True)  # two calls, both in the prefix stage: inlined, no copies of the scene
def shift_prefix(scene: SceneDevice, params: SRParams, r: PrefixReservoir, end: Shading, dst: Shading) -> PrefixShift:
    """Replay r's bounces 0..P-2 from dst with r's numbers, then reconnect the replayed x_{P-1}
    to r's end x_P (`end`). Fails when the replay breaks, when a replayed vertex would end the
    destination's prefix earlier, or when the destination does not end its prefix at x_P (lobe
    not rough there, segment too short, x_P occluded): the shift is then a bijection between the
    prefixes ending at x_P in both pixels (docs/theory/suffix_restir.md#prefix-resampling).
    J = [G p_l]_dst / [G p_l]_src (PSS)."""
    res = PrefixShift()
    if not has_prefix(r) or dst.valid == 0 or end.valid == 0:
        return res
    P = prefix_length(r.flags)
    lobe = prefix_lobe(r.flags)
    hit = dst.hit
    mat = dst.mat
    frame = dst.frame
    wi = dst.wi
    beta = wp.vec3(1.0)
    footprint = dst.hit.t
    k = int(0)
    while k < P - 1:
        sc = scatter_at(hit, mat, frame, wi, r.seed, wp.uint32(0), k)
        if sc.valid == 0:
            return res
        beta = wp.cw_mul(beta, lobe_weight(mat, wi, sc.bs))
        nh = trace_closest(scene, sc.o, sc.d, T_MAX)
        res.rays += 1
        if nh.valid == 0 or max3(beta) <= 0.0:
            return res
        seg = segment(hit.p, hit.ng, nh.p)
        frame_next = shading_frame(scene, nh, -sc.d)
        mat_next = material_at(scene, nh, frame_next)
        if prefix_ends_at(params, k + 1, lobe_is_rough(mat, sc.bs.lobe, params.pt.rough_threshold), mat_next, seg[3]):
            return res  # the destination's prefix would end here, before x_P
        footprint += seg[3]
        hit = nh
        mat = mat_next
        frame = frame_next
        wi = to_local(frame, -sc.d)
        k += 1
    # reconnect x_{P-1} -> x_P with the recorded lobe: the destination's prefix must end at x_P too
    seg = segment(hit.p, hit.ng, end.hit.p)
    dist = seg[3]
    if not prefix_ends_at(params, P, lobe_is_rough(mat, lobe, params.pt.rough_threshold), end.mat, dist):
        return res
    d = wp.vec3(seg[0], seg[1], seg[2])
    e = eval_lobe(mat, wi, to_local(frame, d), lobe)
    cos_end = wp.abs(wp.dot(end.hit.ng, d))
    if e.p <= 0.0 or max3(e.f) <= 0.0 or cos_end <= 0.0:
        return res
    res.rays += 1
    if not visible_to_light(scene, hit.p, hit.ng, d, end.hit.p, end.hit.ng, 0):
        return res
    res.jac = cos_end / (dist * dist) * e.p
    thp = wp.cw_mul(beta, e.f / e.p)
    J = float(0.0)
    if r.jac > 0.0:
        J = res.jac / r.jac
    if luminance(thp) > 0.0 and J > 0.0 and is_finite(J) and is_finite(luminance(thp)):
        res.valid = 1
        res.thp = thp
        res.J = J
        res.dir = d
        res.dist = dist
        res.footprint = footprint + dist
    return res
