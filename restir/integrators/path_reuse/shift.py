"""The shift of a path sample into another pixel's domain: (source path, destination domain: a
primary hit, or a prefix end) -> (the path in the destination, its Jacobian J, valid). One function
for every shift kind and both directions of every MIS weight
(docs/theory/restir_pt.md#the-hybrid-shift).

The destination path replays the source's random numbers from the destination's start vertex (the
same (seed, dim) pairs, so the same numbers whatever the replay skips:
docs/theory/restir_pt.md#random-replay) up to rcPrev, the vertex before the rc vertex z; then
reconnects to z, which both paths share, and keeps everything after z. A path without an rc vertex
is replayed to its end (J = 1).

J is the primary-sample-space Jacobian in the "destination from source" sense: a source sample x
with target p_hat_src(x) has density p_hat_src(x) / J seen from the destination, and its resampling
weight there is m * p_hat_dst(y) * J * W (docs/theory/restir_pt.md#the-reconnection-jacobian):

    J = [G(y', z) p_l(y' -> z) p_l(z -> next | y')] / [the same at the source]

with G = |cos theta_z| / d^2 and p_l single-lobe pdfs; the z factor is left out where z does not
scatter (NEE at z, z an emitter; the environment has no G). The source terms come from the
record (rc_jac); the returned record carries the destination's
(docs/theory/restir_pt.md#what-a-path-sample-stores).

The shift fails (valid = 0, J = 0) when the path is longer than the destination domain holds
(params.max_depth: the same for every ReSTIR PT pixel, max_depth - P for a suffix domain of Suffix
ReSTIR), when the replay does not reach rcPrev, when the destination path would pick a different rc
vertex (an earlier vertex qualifies, or rcPrev/z do not: the hybrid shift is then no bijection:
docs/theory/restir_pt.md#invertibility-and-failed-shifts), when z is occluded or behind a surface,
and when the result is not a finite positive number. A failed shift is still an input: its M counts
and its MIS density is 0 (docs/theory/gris.md#when-a-shift-fails).

`make_shift` builds fault-injected variants for the mutation tests
(docs/validation.md#power-checks-the-mutation-table), each in a Warp module of its own; the shipped
shift (`shift_path`) is built with none.
"""
import warp as wp

from ...device.bounce import found_along, material_at, nee_at, scatter_at, segment, shading_frame
from ...device.bsdf import Material, bsdf_eval, bsdf_is_delta_only, bsdf_pdf, lobe_is_rough
from ...device.color import luminance, max3
from ...device.intersect import T_MAX, SurfaceHit, is_visible, offset_origin, surface_at, trace_closest, visible_to_light
from ...device.lights import env_eval, env_pdf, triangle_emission
from ...device.path_steps import emission_mis_weight
from ...device.sampling import Frame, to_local
from ...device.scene_device import SceneDevice
from ...device.types import STRATEGY_MIS
from ...resampling.ris import is_finite
from ..common.shading import Shading
from .domain import Domain
from .params import SHIFT_HYBRID, PathReuseParams
from .path_sample import (NO_RC, RC_EMITTER, RC_ENV, PathReservoir, ends_on_delta_light, ends_with_nee, holds_path,
                          lobe_at_rc, lobe_at_rc_prev, path_length, rc_kind, rc_length)
from .rc_criteria import (eval_lobe, lobe_weight, qualifies_escape_vertex, qualifies_nee_vertex,
                          qualifies_scatter_vertex)


@wp.struct
class Replay:
    """The destination path replayed up to some vertex: that vertex, the throughput before it, and
    what the rc criteria need about the segment that reached it."""
    valid: int
    hit: SurfaceHit
    mat: Material
    frame: Frame
    wi: wp.vec3
    beta: wp.vec3     # lobe weights of the vertices before this one
    dist_in: float    # its length (0 at the primary hit)
    prev_rough: int   # the lobe sampled at the vertex before was rough
    rays: int


@wp.struct
class ShiftResult:
    r: PathReservoir  # the path in the destination domain: F and rc_jac are the destination's
    J: float
    valid: int
    rays: int


@wp.func
def shift_counts(r: PathReservoir, res: ShiftResult) -> wp.vec4i:
    """One attempted shift for the stats: [attempted with an rc vertex (a reconnection), succeeded,
    attempted without one (pure replay), succeeded]."""
    if rc_length(r.flags) != NO_RC:
        return wp.vec4i(1, res.valid, 0, 0)
    return wp.vec4i(0, 0, 1, res.valid)


MUTATIONS = ("bsdf_twice", "invert_jacobian", "drop_rc_pdf", "keep_source_jacobian", "misaligned_replay",
             "skip_destination_criteria", "delta_light_mis")


_replay_prefixes: dict = {}  # each build's prefix replay, by mutation (tests replay prefixes as the shift does)
_builds: dict = {}  # each build's shift, by (mutation, inline)


def make_shift(mutation: str = "none", inline: bool = False):
    """The shift function; `mutation` (one of MUTATIONS, or "none") builds a fault-injected variant.
    inline: the build that is inlined at its call sites (SHIFT_INLINED below); its functions take
    names of their own, so that a kernel module can hold both builds."""
    assert mutation == "none" or mutation in MUTATIONS, mutation
    if (mutation, inline) in _builds:
        return _builds[mutation, inline]
    module = None if mutation == "none" else f"restir_pt_shift_{mutation}"
    if inline:
        module = f"{module or 'restir_shift'}_inlined"

    def named(fn: str):  # the key of one of this build's functions
        return f"shift_{fn}_inlined_{mutation}" if inline else None
    bsdf_twice = mutation == "bsdf_twice"                # the reconnection's BSDF at rcPrev applied twice
    invert_jacobian = mutation == "invert_jacobian"      # 1/J instead of J
    drop_rc_pdf = mutation == "drop_rc_pdf"              # J without the pdf ratio at z
    keep_source_jacobian = mutation == "keep_source_jacobian"  # cached terms not overwritten
    dim_offset = 1 if mutation == "misaligned_replay" else 0   # replay reads the next bounce's numbers
    check_destination = mutation != "skip_destination_criteria"
    delta_light_mis = mutation == "delta_light_mis"     # NEE at z weighted against BSDF sampling for a delta light too

    @wp.func(module=module, name=named("replay_prefix"))
    def replay_prefix(scene: SceneDevice, params: PathReuseParams, x0: Shading, seed: wp.uint32, n: int) -> Replay:
        """Replay n bounces from x0 with the source path's numbers; invalid when a bounce fails,
        escapes, or reaches a vertex that would be the destination path's rc vertex."""
        y = Replay()
        y.valid = 1
        y.hit = x0.hit
        y.mat = x0.mat
        y.frame = x0.frame
        y.wi = x0.wi
        y.beta = wp.vec3(1.0)
        k = int(0)
        while k < n:
            sc = scatter_at(y.hit, y.mat, y.frame, y.wi, seed, wp.uint32(0), k + dim_offset)
            if sc.valid == 0:
                y.valid = 0
                return y
            if wp.static(check_destination):
                if qualifies_scatter_vertex(params, k, y.dist_in, y.prev_rough != 0, y.mat, sc.bs.lobe):
                    y.valid = 0
                    return y
            y.beta = wp.cw_mul(y.beta, lobe_weight(y.mat, y.wi, sc.bs))
            if max3(y.beta) <= 0.0:
                y.valid = 0
                return y
            nh = trace_closest(scene, sc.o, sc.d, T_MAX)
            y.rays += 1
            if nh.valid == 0:
                y.valid = 0
                return y
            y.prev_rough = wp.where(lobe_is_rough(y.mat, sc.bs.lobe, params.rough_threshold), 1, 0)
            y.dist_in = segment(y.hit.p, y.hit.ng, nh.p)[3]
            y.hit = nh
            y.frame = shading_frame(scene, nh, -sc.d)
            y.mat = material_at(scene, nh, y.frame)
            y.wi = to_local(y.frame, -sc.d)
            k += 1
        return y

    @wp.func(module=module, name=named("replay_end"))
    def replay_end(scene: SceneDevice, params: PathReuseParams, r: PathReservoir, y: Replay) -> ShiftResult:
        """A path without an rc vertex, replayed to its last vertex y: its end event there (J = 1)."""
        res = ShiftResult()
        j = path_length(r.flags)
        seed = r.seed
        F = wp.vec3(0.0)
        if ends_with_nee(r.flags) != 0:
            if bsdf_is_delta_only(y.mat) != 0:
                return res
            if wp.static(check_destination):
                if qualifies_nee_vertex(params, j, y.dist_in, y.prev_rough != 0, y.mat):
                    return res
            c = nee_at(scene, y.hit, y.mat, y.frame, y.wi, seed, wp.uint32(0), j + dim_offset, 1, STRATEGY_MIS)
            res.rays = c.rays
            F = wp.cw_mul(y.beta, c.L)
        else:
            sc = scatter_at(y.hit, y.mat, y.frame, y.wi, seed, wp.uint32(0), j + dim_offset)
            if sc.valid == 0:
                return res
            if wp.static(check_destination):
                if qualifies_scatter_vertex(params, j, y.dist_in, y.prev_rough != 0, y.mat, sc.bs.lobe):
                    return res
            beta = wp.cw_mul(y.beta, lobe_weight(y.mat, y.wi, sc.bs))
            nh = trace_closest(scene, sc.o, sc.d, T_MAX)
            res.rays = 1
            fd = found_along(scene, y.hit, nh, sc.d)
            if wp.static(check_destination):
                rough = lobe_is_rough(y.mat, sc.bs.lobe, params.rough_threshold)
                if qualifies_escape_vertex(params, j + 1, fd.dist, rough, fd.is_env != 0):
                    return res
            F = wp.cw_mul(beta, fd.Le) * emission_mis_weight(sc.bs.is_delta, sc.bs.pdf, fd.p_light, 1, STRATEGY_MIS)
        p_hat = luminance(F)
        if p_hat > 0.0 and is_finite(p_hat):
            res.r = r
            res.r.F = F
            res.J = 1.0
            res.valid = 1
        return res

    @wp.func(module=module, name=named("reconnect"))
    def reconnect(scene: SceneDevice, params: PathReuseParams, r: PathReservoir, y: Replay) -> ShiftResult:
        """Connect the destination's rcPrev y to the source's rc vertex z and keep the rest."""
        res = ShiftResult()
        flags = r.flags
        rcl = rc_length(flags)
        kind = rc_kind(flags)
        lobe_prev = lobe_at_rc_prev(flags)
        hybrid = params.shift == SHIFT_HYBRID
        if wp.static(check_destination):
            # y must sample the recorded lobe as a rough one, and must not itself qualify as z
            if hybrid and not lobe_is_rough(y.mat, lobe_prev, params.rough_threshold):
                return res
            if qualifies_scatter_vertex(params, rcl - 1, y.dist_in, y.prev_rough != 0, y.mat, lobe_prev):
                return res
        F = wp.vec3(0.0)
        w_y = wp.vec3(0.0)
        jac = wp.vec2(0.0)
        if kind == RC_ENV:
            w1 = r.rc_wi
            wo_y = to_local(y.frame, w1)
            e = eval_lobe(y.mat, y.wi, wo_y, lobe_prev)
            if e.p <= 0.0 or max3(e.f) <= 0.0:
                return res
            res.rays = 1
            if not is_visible(scene, offset_origin(y.hit.p, y.hit.ng, w1), w1, T_MAX):
                return res
            w_y = e.f / e.p
            mis = emission_mis_weight(0, bsdf_pdf(y.mat, y.wi, wo_y), env_pdf(scene, w1), 1, STRATEGY_MIS)
            F = wp.cw_mul(w_y, env_eval(scene, w1)) * mis
            jac = wp.vec2(e.p, 1.0)
        else:
            z = surface_at(scene, r.rc_tri, r.rc_bary[0], r.rc_bary[1], 0.0)
            seg = segment(y.hit.p, y.hit.ng, z.p)
            dist = seg[3]
            if dist <= 0.0:
                return res
            w1 = wp.vec3(seg[0], seg[1], seg[2])
            if wp.static(check_destination):
                if hybrid and dist < params.near_distance:
                    return res
            wo_y = to_local(y.frame, w1)
            e = eval_lobe(y.mat, y.wi, wo_y, lobe_prev)
            cos_z = wp.abs(wp.dot(z.ng, w1))
            if e.p <= 0.0 or max3(e.f) <= 0.0 or cos_z <= 0.0:
                return res
            G = cos_z / (dist * dist)
            res.rays = 1
            if not visible_to_light(scene, y.hit.p, y.hit.ng, w1, z.p, z.ng, 0):
                return res
            w_y = e.f / e.p
            if kind == RC_EMITTER:
                Le = triangle_emission(scene, r.rc_tri, z.ns, -w1)
                # the light pdf from y, converted from the stored area measure
                # (docs/theory/restir_pt.md#what-a-path-sample-stores)
                mis = emission_mis_weight(0, bsdf_pdf(y.mat, y.wi, wo_y), r.light_pdf * dist * dist / cos_z, 1,
                                          STRATEGY_MIS)
                F = wp.cw_mul(w_y, Le) * mis
                jac = wp.vec2(G * e.p, 1.0)
            else:
                frame_z = shading_frame(scene, z, -w1)
                mat_z = material_at(scene, z, frame_z)
                wi_z = to_local(frame_z, -w1)
                wo_z = to_local(frame_z, r.rc_wi)
                if ends_with_nee(flags) != 0 and path_length(flags) == rcl:
                    # NEE at z: all lobes, and the MIS weight against BSDF sampling at z's new wi
                    # (none for a delta light, which BSDF sampling cannot reach: weight 1). The light
                    # sample itself does not move (z does not), so J has no factor at the light.
                    f_z = bsdf_eval(mat_z, wi_z, wo_z)
                    p_sum = r.light_pdf
                    if ends_on_delta_light(flags) == 0 or wp.static(delta_light_mis):
                        p_sum += bsdf_pdf(mat_z, wi_z, wo_z)
                    F = wp.cw_mul(w_y, wp.cw_mul(f_z, r.rc_L)) / p_sum
                    jac = wp.vec2(G * e.p, 1.0)
                else:
                    ez = eval_lobe(mat_z, wi_z, wo_z, lobe_at_rc(flags))
                    if ez.p <= 0.0:
                        return res
                    after = r.rc_L
                    if path_length(flags) == rcl:  # emission found from z: its MIS weight at z's new wi
                        after = after * emission_mis_weight(0, bsdf_pdf(mat_z, wi_z, wo_z), r.light_pdf, 1,
                                                            STRATEGY_MIS)
                    F = wp.cw_mul(w_y, wp.cw_mul(ez.f / ez.p, after))
                    jac = wp.vec2(G * e.p, ez.p)
        F = wp.cw_mul(y.beta, F)
        if wp.static(bsdf_twice):
            F = wp.cw_mul(F, w_y)
        J = float(0.0)
        src = r.rc_jac[0] * r.rc_jac[1]
        if src > 0.0:
            J = jac[0] * jac[1] / src
        if wp.static(drop_rc_pdf):
            J = 0.0
            if r.rc_jac[0] > 0.0:
                J = jac[0] / r.rc_jac[0]
        if wp.static(invert_jacobian):
            if J > 0.0:
                J = 1.0 / J
        p_hat = luminance(F)
        if p_hat > 0.0 and J > 0.0 and is_finite(p_hat) and is_finite(J):
            res.r = r
            res.r.F = F
            if wp.static(not keep_source_jacobian):
                res.r.rc_jac = jac
            res.J = J
            res.valid = 1
        return res

    # Out of line (CUDA __noinline__) in the default build: called from several places of one
    # kernel (Suffix ReSTIR's gather makes several shifts per gathered prefix), inlined copies made
    # the CUDA build of a module take minutes. The inlined build (SHIFT_INLINED) serves the kernels
    # that shift in one or two places.
    @wp.func(module=module, inline=inline, name=named("path"))
    def shift_path(scene: SceneDevice, r: PathReservoir, dst: Domain) -> ShiftResult:
        """r's path moved into the domain dst (see the module docstring); invalid if it fails."""
        res = ShiftResult()
        params = dst.params
        if not holds_path(r) or dst.sh.valid == 0:
            return res
        if path_length(r.flags) + 2 > params.max_depth:
            return res  # longer than the destination domain holds (suffix domains: max_depth - P)
        rcl = rc_length(r.flags)
        n = path_length(r.flags)
        if rcl != NO_RC:
            n = rcl - 1
        y = replay_prefix(scene, params, dst.sh, r.seed, n)
        if y.valid == 0:
            res.rays = y.rays
            return res
        if rcl == NO_RC:
            res = replay_end(scene, params, r, y)
        else:
            res = reconnect(scene, params, r, y)
        res.rays += y.rays
        return res

    shift_path.inlined = inline  # make_reuse_pair inlines the spatial step around an inlined shift
    if not inline:
        _replay_prefixes[mutation] = replay_prefix
    _builds[mutation, inline] = shift_path
    return shift_path


shift_path = make_shift()
# The reuse passes that shift in one or two places call the shift inlined (ReSTIR PT's temporal and
# spatial kernels, Suffix ReSTIR's suffix temporal and spatial kernels): out of line, every call
# copies its arguments (Warp passes structs by value: SceneDevice alone is 1152 B) and the compiler
# cannot fit it to the call site. Inlined, ReSTIR PT's spatial pass took 0.7x as long and its
# frame 0.88x at 512x512; Suffix ReSTIR's frame 0.96-0.98x
# (docs/changelog.md#speed-functions-that-copied-the-scene-inlined).
# Each inlined copy lengthens the module's build (ReSTIR PT's CUDA build 80 -> 107 s, Suffix
# ReSTIR's 80 -> 109 s), so the gather, which shifts in several places, keeps the out-of-line build.
SHIFT_INLINED = make_shift(inline=True)
replay_prefix = _replay_prefixes["none"]
