"""The base path tracer of ReSTIR PT with streaming RIS over path lengths
(docs/theory/restir_pt.md#initial-resampling-over-path-lengths).

One base path starts at a pixel's primary hit x_0 and is traced with the device steps every
method shares (device/path_steps.py: light connection, emission MIS weight, scattering), with
the lobe-separated path BSDF. Every event it makes is a candidate: NEE at x_k, and emission
(or the environment) found by BSDF sampling from x_k, for k >= first_event (1 when ReSTIR DI
owns direct light at x_0, 0 when ReSTIR PT owns every path). Each event lives in its own
sub-domain (its length and end type), so the path's candidates are resampled with unit MIS
weights, w = p_hat(F) (p_source = 1 in primary sample space; no Russian roulette), and the
path counts M = 1 however many events it has. With C paths per pixel each event is
weighted 1/C and M = C.

With direct=nee (params.direct_nee) the events at x_0 are summed into `direct` instead, as the
path tracer sums them, and resampling starts at x_1 (first_event = 1): the same partition of the
paths as with ReSTIR DI owning x_0's light, with the path tracer's estimator for that part.

While tracing, the path keeps its rc vertex (rc_criteria.py) and splits its throughput into
the part up to and including rcPrev's bounce (beta) and the part after z's own bounce
(beta_rc), so that an event's record holds exactly what a reconnection needs (path_sample.py).
"""
import warp as wp

from ...device.bounce import found_along, material_at, nee_at, scatter_at, shading_frame
from ...device.bsdf import bsdf_is_delta_only, bsdf_pdf_lobes, lobe_is_rough
from ...device.color import luminance, max3
from ...device.intersect import T_MAX, trace_closest
from ...device.path_steps import emission_mis_weight
from ...device.rng import rng_uniform
from ...device.scene_device import SceneDevice
from ...device.sampling import to_local
from ...device.streams import PT_RIS_DIM_EMISSION, PT_RIS_DIM_NEE, PT_RIS_DIMS_PER_VERTEX
from ...device.types import STRATEGY_MIS
from ...resampling.ris import RisState, ris_stream
from ..common.shading import Shading
from .params import PathReuseParams
from .path_sample import (MAX_PATH_LENGTH, NO_RC, RC_EMITTER, RC_ENV, RC_SURFACE, PathReservoir, pack_flags,
                          with_delta_light)
from .rc_criteria import lobe_pdf, lobe_weight, qualifies_escape_vertex, qualifies_nee_vertex, qualifies_scatter_vertex

EVENTS_PER_PATH = 2 * (MAX_PATH_LENGTH + 2)  # event indices of candidate c: c * EVENTS_PER_PATH + ...


@wp.struct
class BasePath:
    """The pixel's streaming-RIS state over its base paths so far, the selected event's record,
    and the rays traced."""
    s: RisState
    r: PathReservoir
    rays: int
    direct: wp.vec3  # direct=nee: the events at x_0, summed (each weighted 1/C)


@wp.func
def event_record(F: wp.vec3, flags: int, seed: wp.uint32, rc_tri: int, rc_bary: wp.vec2, rc_wi: wp.vec3,
                 rc_L: wp.vec3, rc_jac: wp.vec2, light_pdf: float) -> PathReservoir:
    r = PathReservoir()
    r.F = F
    r.flags = flags
    r.seed = seed
    r.rc_tri = rc_tri
    r.rc_bary = rc_bary
    r.rc_wi = rc_wi
    r.rc_L = rc_L
    r.rc_jac = rc_jac
    r.light_pdf = light_pdf
    return r


@wp.func(inline=False)  # out of line: one copy per module however many stages trace base paths
def trace_base_path(scene: SceneDevice, params: PathReuseParams, x0: Shading, seed: wp.uint32, ris_key: wp.uint32,
                    index_base: int, acc: BasePath) -> BasePath:
    """Trace one base path from the primary hit x0 with random-number key `seed` and stream its
    events into acc (event indices index_base + 2k + {0, 1}; selections drawn from ris_key)."""
    out = acc
    scale = 1.0 / float(params.candidates)
    hit = x0.hit
    mat = x0.mat
    frame = x0.frame
    wi = x0.wi
    beta = wp.vec3(1.0)      # lobe weights of x_0 .. x_{k-1}
    beta_rc = wp.vec3(1.0)   # lobe weights after the rc vertex's own bounce
    rc_len = int(NO_RC)
    rc_tri = int(-1)
    rc_bary = wp.vec2(0.0)
    rc_wi = wp.vec3(0.0)
    rc_jac = wp.vec2(0.0)
    lobe_prev_rc = int(0)
    lobe_rc = int(0)
    prev_lobe = int(0)
    prev_rough = bool(False)
    jac_in = float(0.0)      # G(x_{k-1}, x_k) p_l(x_{k-1} -> x_k), both from the vertex positions
    dist_in = float(0.0)     # |x_k - x_{k-1}|
    k = int(0)
    while k + 2 <= params.max_depth:
        # x_k's events are resampled (k >= first_event) or, with direct=nee at x_0, summed
        resampled = k >= params.first_event
        summed = params.direct_nee != 0 and k == 0
        # ---- NEE at x_k: an event of length k
        if (resampled or summed) and bsdf_is_delta_only(mat) == 0:
            c = nee_at(scene, hit, mat, frame, wi, seed, wp.uint32(0), k, 1, STRATEGY_MIS)
            out.rays += c.rays
            F = wp.cw_mul(beta, c.L)
            if summed:
                out.direct += F * scale
            p_hat = luminance(F)
            index = index_base + PT_RIS_DIMS_PER_VERTEX * k + PT_RIS_DIM_NEE
            if resampled:
                out.s = ris_stream(out.s, p_hat * scale, p_hat, 0.0, index, rng_uniform(ris_key, wp.uint32(
                    PT_RIS_DIMS_PER_VERTEX * k + PT_RIS_DIM_NEE)))
            if resampled and out.s.selected == index:
                if rc_len != NO_RC:
                    out.r = event_record(F, pack_flags(k, rc_len, lobe_prev_rc, lobe_rc, 1, RC_SURFACE), seed, rc_tri,
                                         rc_bary, rc_wi, wp.cw_mul(beta_rc, c.L), rc_jac, c.p_light)
                elif qualifies_nee_vertex(params, k, dist_in, prev_rough, mat):
                    out.r = event_record(F, pack_flags(k, k, prev_lobe, 0, 1, RC_SURFACE), seed, hit.tri, hit.bary,
                                         c.wi, c.Le, wp.vec2(jac_in, 1.0), c.p_light)
                else:
                    out.r = event_record(F, pack_flags(k, NO_RC, 0, 0, 1, RC_SURFACE), seed, -1, wp.vec2(0.0),
                                         wp.vec3(0.0), wp.vec3(0.0), wp.vec2(0.0), c.p_light)
                out.r.flags = with_delta_light(out.r.flags, c.is_delta)
        # ---- BSDF sampling at x_k
        sc = scatter_at(hit, mat, frame, wi, seed, wp.uint32(0), k)
        if sc.valid == 0:
            break
        w = lobe_weight(mat, wi, sc.bs)
        p_lobe = lobe_pdf(mat, wi, sc.bs)
        rough = lobe_is_rough(mat, sc.bs.lobe, params.rough_threshold)
        if rc_len == NO_RC and qualifies_scatter_vertex(params, k, dist_in, prev_rough, mat, sc.bs.lobe):
            rc_len = k
            rc_tri = hit.tri
            rc_bary = hit.bary
            rc_wi = sc.d
            rc_jac = wp.vec2(jac_in, p_lobe)
            lobe_prev_rc = prev_lobe
            lobe_rc = sc.bs.lobe
            beta_rc = wp.vec3(1.0)
        elif rc_len != NO_RC:
            beta_rc = wp.cw_mul(beta_rc, w)
        beta = wp.cw_mul(beta, w)
        if max3(beta) <= 0.0:
            break
        nh = trace_closest(scene, sc.o, sc.d, T_MAX)
        out.rays += 1
        # ---- emission found from x_k (or the environment): an event of length k
        fd = found_along(scene, hit, nh, sc.d)
        is_env = fd.is_env != 0
        Le = fd.Le
        p_light = fd.p_light
        dist = fd.dist
        jac_next = float(0.0)
        if rc_len == NO_RC and not is_env and dist > 0.0:
            # the source terms of J as a shift will compute them, from the segment between the
            # two vertices (rc_criteria.segment)
            jac_next = wp.abs(wp.dot(nh.ng, fd.dir)) / (dist * dist) * bsdf_pdf_lobes(mat, wi, to_local(frame, fd.dir),
                                                                                        sc.bs.lobe)
        if (resampled or summed) and max3(Le) > 0.0:
            mis = emission_mis_weight(sc.bs.is_delta, sc.bs.pdf, p_light, 1, STRATEGY_MIS)
            F = wp.cw_mul(beta, Le) * mis
            if summed:
                out.direct += F * scale
            p_hat = luminance(F)
            index = index_base + PT_RIS_DIMS_PER_VERTEX * k + PT_RIS_DIM_EMISSION
            if resampled:
                out.s = ris_stream(out.s, p_hat * scale, p_hat, 0.0, index, rng_uniform(ris_key, wp.uint32(
                    PT_RIS_DIMS_PER_VERTEX * k + PT_RIS_DIM_EMISSION)))
            if resampled and out.s.selected == index:
                if rc_len != NO_RC and rc_len < k:
                    out.r = event_record(F, pack_flags(k, rc_len, lobe_prev_rc, lobe_rc, 0, RC_SURFACE), seed, rc_tri,
                                         rc_bary, rc_wi, wp.cw_mul(beta_rc, Le) * mis, rc_jac, p_light)
                elif rc_len == k:
                    out.r = event_record(F, pack_flags(k, k, lobe_prev_rc, lobe_rc, 0, RC_SURFACE), seed, rc_tri,
                                         rc_bary, rc_wi, Le, rc_jac, p_light)
                elif qualifies_escape_vertex(params, k + 1, dist, rough, is_env):
                    if is_env:
                        out.r = event_record(F, pack_flags(k, k + 1, sc.bs.lobe, 0, 0, RC_ENV), seed, -1, wp.vec2(0.0),
                                             sc.d, Le, wp.vec2(p_lobe, 1.0), p_light)
                    else:
                        p_area = (1.0 - scene.env_select_prob) * scene.tri_light_pdf[nh.tri]
                        out.r = event_record(F, pack_flags(k, k + 1, sc.bs.lobe, 0, 0, RC_EMITTER), seed, nh.tri,
                                             nh.bary, sc.d, Le, wp.vec2(jac_next, 1.0), p_area)
                else:
                    out.r = event_record(F, pack_flags(k, NO_RC, 0, 0, 0, RC_SURFACE), seed, -1, wp.vec2(0.0),
                                         wp.vec3(0.0), wp.vec3(0.0), wp.vec2(0.0), p_light)
        if is_env:
            break
        # ---- on to x_{k+1}
        prev_lobe = sc.bs.lobe
        prev_rough = rough
        jac_in = jac_next
        dist_in = dist
        hit = nh
        frame = shading_frame(scene, hit, -sc.d)
        mat = material_at(scene, hit, frame)
        wi = to_local(frame, -sc.d)
        k += 1
    return out
