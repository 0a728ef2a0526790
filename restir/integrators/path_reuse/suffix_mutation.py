"""An MCMC mutation of a path sample's suffix: a fresh suffix after its reconnection vertex z,
proposed with numbers from a stream of its own (docs/guide/decorrelation.md 2; Sawhney et al. 2024,
"Decorrelating ReSTIR Samplers via MCMC Mutations").

A path sample held in a pixel's domain is the pixel's prefix up to rcPrev (fixed by the sample's
seed), the reconnection to z, and a suffix after z that only the record's cached fields hold
(`rc_wi`, `rc_L`, `light_pdf`, `rc_jac[1]`, the lobe at z). In primary sample space the suffix
is the uniform numbers u_suf of z's light sample or scatter and of every bounce after it. The
proposal redraws u_suf uniformly (density 1 both ways, so the acceptance is the target ratio)
and keeps everything else: the event (path length, end type), z, the prefix. It is rejected
when it leaves the sample's class, i.e. when the base path tracer with these numbers would not
make the same event with z as its rc vertex: a scatter at z whose lobe no longer qualifies, a
path that ends (escapes, fails to scatter) before its event, an end event of zero value.
Restricted to a class, the kernel is a Metropolis kernel of p_hat, so it leaves p_hat invariant,
and W_Y = W_X p_hat(X) / p_hat(Y) keeps (Y, W_Y) an unbiased pair (decorrelation.md 2).

Two starts: after z (z stays; `mcmc.start=z`) or after rcPrev (a fresh scatter at rcPrev finds a
new z; `mcmc.start=rc_prev`). Either way the redrawn numbers are a block of the sample's primary
sample space coordinates, so the same argument holds.
"""
import warp as wp

from ...device.bounce import found_along, material_at, nee_at, scatter_at, segment, shading_frame
from ...device.bsdf import bsdf_is_delta_only, bsdf_pdf_lobes, lobe_is_rough
from ...device.color import max3
from ...device.intersect import T_MAX, surface_at, trace_closest
from ...device.path_steps import emission_mis_weight
from ...device.sampling import to_local
from ...device.scene_device import SceneDevice
from ...device.types import STRATEGY_MIS
from .params import PathReuseParams
from .path_sample import (NO_RC, RC_SURFACE, PathReservoir, ends_with_nee, holds_path, lobe_at_rc_prev, path_length,
                          rc_kind, rc_length, with_delta_light, with_lobe_at_rc, with_lobe_at_rc_prev)
from .rc_criteria import lobe_pdf, lobe_weight, qualifies_nee_vertex, qualifies_scatter_vertex
from .shift import Replay


@wp.struct
class SuffixProposal:
    r: PathReservoir  # the sample with the proposed suffix in its cached fields (F not yet evaluated)
    valid: int        # 0: the proposal left the sample's class (a rejection)
    rays: int


@wp.func
def mutable(r: PathReservoir) -> bool:
    """The sample has a suffix the record alone holds: a surface rc vertex z. (A path without one
    is replayed whole from its seed; an emitter or environment rc has no numbers after z.)"""
    return holds_path(r) and rc_length(r.flags) != NO_RC and rc_kind(r.flags) == RC_SURFACE


@wp.func
def propose_suffix(scene: SceneDevice, params: PathReuseParams, r: PathReservoir, y: Replay, key: wp.uint32,
                   from_rc_prev: int) -> SuffixProposal:
    """r's path redrawn after z (from_rc_prev = 0) or after rcPrev (1: z moves too) with the
    numbers of `key` (the base paths' per-bounce layout, from the first redrawn vertex's index
    on); y is the pixel's prefix replayed to rcPrev."""
    out = SuffixProposal()
    out.r = r
    flags = r.flags
    rcl = rc_length(flags)
    j = path_length(flags)
    prev_rough = lobe_is_rough(y.mat, lobe_at_rc_prev(flags), params.rough_threshold)
    hit = y.hit
    lobe_prev = int(0)
    if from_rc_prev != 0:
        # a fresh scatter at rcPrev finds a new z; rcPrev must still not qualify (z must be the
        # first vertex that does)
        sp = scatter_at(y.hit, y.mat, y.frame, y.wi, key, wp.uint32(0), rcl - 1)
        if sp.valid == 0:
            return out
        if qualifies_scatter_vertex(params, rcl - 1, y.dist_in, y.prev_rough != 0, y.mat, sp.bs.lobe):
            return out
        lobe_prev = sp.bs.lobe
        hit = trace_closest(scene, sp.o, sp.d, T_MAX)
        out.rays += 1
        if hit.valid == 0:
            return out
    else:
        hit = surface_at(scene, r.rc_tri, r.rc_bary[0], r.rc_bary[1], 0.0)
    seg = segment(y.hit.p, y.hit.ng, hit.p)
    d = wp.vec3(seg[0], seg[1], seg[2])  # rcPrev -> z
    dist = seg[3]
    if dist <= 0.0:
        return out
    if from_rc_prev != 0:
        # the new z: its record, and the segment's source terms of J
        prev_rough = lobe_is_rough(y.mat, lobe_prev, params.rough_threshold)
        out.r.rc_tri = hit.tri
        out.r.rc_bary = hit.bary
        out.r.rc_jac = wp.vec2(wp.abs(wp.dot(hit.ng, d)) / (dist * dist) * bsdf_pdf_lobes(
            y.mat, y.wi, to_local(y.frame, d), lobe_prev), r.rc_jac[1])
        out.r.flags = with_lobe_at_rc_prev(flags, lobe_prev)
    frame = shading_frame(scene, hit, -d)
    mat = material_at(scene, hit, frame)
    wi = to_local(frame, -d)
    if j == rcl and ends_with_nee(flags) != 0:
        # NEE at z: a fresh light sample (z must qualify on its material: fixed unless z moved)
        if bsdf_is_delta_only(mat) != 0 or not qualifies_nee_vertex(params, rcl, dist, prev_rough, mat):
            return out
        c = nee_at(scene, hit, mat, frame, wi, key, wp.uint32(0), rcl, 1, STRATEGY_MIS)
        out.rays += c.rays
        out.r.rc_wi = c.wi
        out.r.rc_L = c.Le
        out.r.light_pdf = c.p_light
        out.r.flags = with_delta_light(out.r.flags, c.is_delta)  # the fresh sample's light may be another kind
        out.valid = wp.where(max3(c.L) > 0.0, 1, 0)
        return out
    # ---- z's own scatter: its lobe must still make z the rc vertex
    sc = scatter_at(hit, mat, frame, wi, key, wp.uint32(0), rcl)
    if sc.valid == 0:
        return out
    if not qualifies_scatter_vertex(params, rcl, dist, prev_rough, mat, sc.bs.lobe):
        return out
    out.r.rc_wi = sc.d
    out.r.rc_jac = wp.vec2(out.r.rc_jac[0], lobe_pdf(mat, wi, sc.bs))
    out.r.flags = with_lobe_at_rc(out.r.flags, sc.bs.lobe)
    beta = wp.vec3(1.0)  # lobe weights after z's own bounce (the base path's beta_rc)
    k = rcl
    while k <= j:
        nh = trace_closest(scene, sc.o, sc.d, T_MAX)
        out.rays += 1
        fd = found_along(scene, hit, nh, sc.d)
        if k == j:
            # emission found by x_j's scatter ends the path; from z itself its MIS weight is
            # recomputed by the shift, so rc_L is Le alone there
            L = fd.Le
            if k > rcl:
                L = wp.cw_mul(beta, fd.Le) * emission_mis_weight(sc.bs.is_delta, sc.bs.pdf, fd.p_light, 1,
                                                                 STRATEGY_MIS)
            out.r.rc_L = L
            out.r.light_pdf = fd.p_light
            out.valid = wp.where(max3(L) > 0.0, 1, 0)
            return out
        if fd.is_env != 0:
            return out  # the path ended before its event
        hit = nh
        frame = shading_frame(scene, hit, -sc.d)
        mat = material_at(scene, hit, frame)
        wi = to_local(frame, -sc.d)
        k += 1
        if k == j and ends_with_nee(flags) != 0:
            if bsdf_is_delta_only(mat) != 0:
                return out
            c = nee_at(scene, hit, mat, frame, wi, key, wp.uint32(0), k, 1, STRATEGY_MIS)
            out.rays += c.rays
            out.r.rc_L = wp.cw_mul(beta, c.L)
            out.r.light_pdf = c.p_light
            out.r.flags = with_delta_light(out.r.flags, c.is_delta)
            out.valid = wp.where(max3(c.L) > 0.0, 1, 0)
            return out
        sc = scatter_at(hit, mat, frame, wi, key, wp.uint32(0), k)
        if sc.valid == 0:
            return out
        beta = wp.cw_mul(beta, lobe_weight(mat, wi, sc.bs))
        if max3(beta) <= 0.0:
            return out
    return out

