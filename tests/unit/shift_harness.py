"""The shift tests' device harnesses, shared by the ReSTIR PT and Suffix ReSTIR shift tests (the
same shift on two kinds of domain): test kernels that call the production shift
(path_reuse/shift.py) over every pixel pair.

- Round trips (D2, D3; the properties in tests/unit/test_pt_shifts.py): `run_round_trips` shifts
  each pixel's path to its partner and back, `assert_identity_and_round_trip` checks identity,
  J J' = 1 and that a shift succeeds iff its inverse does.
- Finite-difference Jacobians (D5; the derivation in tests/unit/test_pt_jacobian_fd.py):
  `run_fd` takes J of the shift by central differences in primary sample space through the
  production samplers and ray tracing; `well_conditioned`, `relative_errors` and `describe`
  select, compare and report the rows.
"""
import numpy as np
import warp as wp

from restir.device.bsdf import Material, bsdf_sample
from restir.device.bsdfs.material import microfacet_of
from restir.device.intersect import T_MAX, surface_at, trace_closest
from restir.device.microfacet import microfacet_sample_to_square
from restir.device.path_steps import scatter
from restir.device.rng import rng_uniform, rng_uniform2
from restir.device.sampling import cosine_hemisphere_to_square, frame_from_normal, to_local
from restir.device.scene_device import SceneDevice, textured_material
from restir.device.streams import DIM_BSDF_DIR, DIM_BSDF_LOBE
from restir.device.types import LOBE_DIFFUSE_REFLECTION, MAT_PLASTIC, MAT_ROUGHPLASTIC
from restir.integrators.common.gbuffer import GBuffer
from restir.integrators.common.shading import load_shading
from restir.device.bounce import bounce_dim, segment
from restir.integrators.path_reuse.domain import domain_at
from restir.integrators.path_reuse.params import PathReuseParams
from restir.integrators.path_reuse.path_sample import (NO_RC, RC_ENV, RC_SURFACE, PathReservoir, ends_with_nee,
                                                      holds_path, lobe_at_rc, lobe_at_rc_prev, path_length, rc_kind,
                                                      rc_length)
from restir.integrators.path_reuse.shift import Replay, _replay_prefixes, make_shift, shift_path


def base_paths(scene, shift, direct="restir-di", max_depth=5, device="cpu"):
    """One frame of ReSTIR PT's base paths on `scene` (no reuse): (integrator, their reservoirs,
    the G-buffer of their primary hits)."""
    import restir
    from restir.api import make_integrator

    cfg = restir.RenderConfig(method="restir-pt", spp=1, frames=1, seed=7, device=device,
                              max_depth=max_depth,
                              settings={"shift": shift, "direct": direct, "temporal": False, "spatial.rounds": 0})
    integ = make_integrator(scene, cfg)
    integ.render_frame(0)
    # after the frame, the final reservoirs and G-buffer are the "previous" ones
    return integ, integ.reservoirs.previous, integ.gbuffers.previous


H = 4.0e-3
N_OUT = 10  # [ok, J (shift), J (finite differences), rc length, rc kind, z factor, material at z, at rcPrev,


@wp.func
def flip_to_front(mat: Material, wi: wp.vec3, v: wp.vec3) -> wp.vec3:
    if mat.twosided != 0 and wi[2] < 0.0:
        return wp.vec3(v[0], v[1], -v[2])
    return v


@wp.func
def lobe_to_square(mat: Material, wi_in: wp.vec3, wo_in: wp.vec3, lobe: int) -> wp.vec2:
    """The direction numbers u with which `lobe` samples wo_in given wi_in (reflection lobes)."""
    wi = flip_to_front(mat, wi_in, wi_in)
    wo = flip_to_front(mat, wi_in, wo_in)
    if lobe == LOBE_DIFFUSE_REFLECTION:
        return cosine_hemisphere_to_square(wo)
    return microfacet_sample_to_square(microfacet_of(mat), wi, wp.normalize(wi + wo))


@wp.func
def lobe_probability(mat: Material, wi: wp.vec3, lobe: int) -> float:
    """The length of the u_lobe interval with which the production sampler picks `lobe` (the
    coat below the boundary, the diffuse base above it); 1 for materials with one smooth lobe."""
    if mat.kind != MAT_ROUGHPLASTIC and mat.kind != MAT_PLASTIC:
        return 1.0
    lo = float(0.0)
    hi = float(1.0)
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        if bsdf_sample(mat, wi, mid, wp.vec2(0.5, 0.5)).lobe == LOBE_DIFFUSE_REFLECTION:
            hi = mid
        else:
            lo = mid
    b = 0.5 * (lo + hi)
    if lobe == LOBE_DIFFUSE_REFLECTION:
        return 1.0 - b
    return b


@wp.func
def wrapped(d: wp.vec2) -> wp.vec2:
    """A difference of two numbers in [0, 1) across the wrap-around of an angle coordinate."""
    out = d
    for c in range(2):
        if out[c] > 0.5:
            out[c] = out[c] - 1.0
        if out[c] < -0.5:
            out[c] = out[c] + 1.0
    return out


@wp.func
def piece(lobe: int, u: wp.vec2) -> int:
    """Which of the concentric map's four pieces u lies in (diffuse lobes; 0 otherwise): the map
    is not differentiable across their seams, so a difference may not straddle one."""
    if lobe != LOBE_DIFFUSE_REFLECTION:
        return 0
    a = 2.0 * u[0] - 1.0
    b = 2.0 * u[1] - 1.0
    if wp.abs(a) > wp.abs(b):
        return wp.where(a > 0.0, 0, 1)
    return wp.where(b > 0.0, 2, 3)


@wp.struct
class Target:
    ok: int
    p: wp.vec3  # z's position, or the direction to the environment


@wp.func
def target_from(scene: SceneDevice, x: Replay, u_lobe: float, u: wp.vec2, lobe: int, kind: int, tri: int) -> Target:
    """Where the source's bounce at rcPrev x goes with the numbers (u_lobe, u)."""
    t = Target()
    sc = scatter(x.hit, x.mat, x.frame, x.wi, u_lobe, u)
    if sc.valid == 0 or sc.bs.lobe != lobe:
        return t
    if kind == RC_ENV:
        t.p = sc.d
        t.ok = wp.where(trace_closest(scene, sc.o, sc.d, T_MAX).valid == 0, 1, 0)
        return t
    nh = trace_closest(scene, sc.o, sc.d, T_MAX)
    if nh.valid != 0 and nh.tri == tri:
        t.ok = 1
        t.p = nh.p
    return t


@wp.func
def u_toward(y: Replay, target: wp.vec3, kind: int, lobe: int) -> wp.vec2:
    d = target
    if kind != RC_ENV:
        seg = segment(y.hit.p, y.hit.ng, target)
        d = wp.vec3(seg[0], seg[1], seg[2])
    return lobe_to_square(y.mat, y.wi, to_local(y.frame, d), lobe)


@wp.func
def central_difference(lobe: int, u0: wp.vec2, e: wp.vec2, u_dst: wp.vec2, ua: wp.vec2, ub: wp.vec2) -> wp.vec3:
    """(u'(u0 + e) - u'(u0 - e)) / 2|e| as (du'/du_k, 1), from ua = u'(u0 + e), ub = u'(u0 - e) and
    u_dst = u'(u0); 0 when the three points do not lie in one piece of the lobe's warp on both sides."""
    p_src = piece(lobe, u0)
    p_dst = piece(lobe, u_dst)
    if piece(lobe, u0 + e) != p_src or piece(lobe, u0 - e) != p_src or piece(lobe, ua) != p_dst or \
            piece(lobe, ub) != p_dst:
        return wp.vec3(0.0)
    d = wrapped(ua - ub) / (2.0 * wp.length(e))
    return wp.vec3(d[0], d[1], 1.0)


@wp.func
def column_at_rc_prev(scene: SceneDevice, xr: Replay, yr: Replay, ul: float, u0: wp.vec2, k: int, h: float,
                      lobe: int, kind: int, tri: int) -> wp.vec3:
    """Central difference of u -> u' along u[k] with step h: (du'/du_k, 1), or 0 where a perturbed
    bounce misses z's triangle or picks another lobe."""
    e = wp.vec2(0.0)
    e[k] = h
    a = target_from(scene, xr, ul, u0 + e, lobe, kind, tri)
    b = target_from(scene, xr, ul, u0 - e, lobe, kind, tri)
    if a.ok == 0 or b.ok == 0:
        return wp.vec3(0.0)
    u_dst = u_toward(yr, target_from(scene, xr, ul, u0, lobe, kind, tri).p, kind, lobe)
    return central_difference(lobe, u0, e, u_dst, u_toward(yr, a.p, kind, lobe), u_toward(yr, b.p, kind, lobe))


@wp.func
def column_at_z(mat: Material, wi_src: wp.vec3, wi_dst: wp.vec3, ul: float, u0: wp.vec2, k: int, h: float,
                lobe: int) -> wp.vec3:
    """The same at z: u -> w_o (sampled with the source's incoming direction) -> u' (with the
    destination's)."""
    e = wp.vec2(0.0)
    e[k] = h
    sa = bsdf_sample(mat, wi_src, ul, u0 + e)
    sb = bsdf_sample(mat, wi_src, ul, u0 - e)
    if sa.valid == 0 or sb.valid == 0 or sa.lobe != lobe or sb.lobe != lobe:
        return wp.vec3(0.0)
    u_dst = lobe_to_square(mat, wi_dst, bsdf_sample(mat, wi_src, ul, u0).wo, lobe)
    return central_difference(lobe, u0, e, u_dst, lobe_to_square(mat, wi_dst, sa.wo, lobe),
                              lobe_to_square(mat, wi_dst, sb.wo, lobe))


@wp.func
def richardson(c_h: wp.vec3, c_h2: wp.vec3) -> wp.vec3:
    """Richardson extrapolation of central differences with steps h and h/2 (error O(h^4)): short
    segments make u -> z strongly curved."""
    if c_h[2] == 0.0 or c_h2[2] == 0.0:
        return wp.vec3(0.0)
    return wp.vec3((4.0 * c_h2[0] - c_h[0]) / 3.0, (4.0 * c_h2[1] - c_h[1]) / 3.0, 1.0)


@wp.func
def grazing_cos(scene: SceneDevice, xr: Replay, yr: Replay, target: wp.vec3, kind: int, tri: int) -> float:
    """The smallest |cos| between a reconnection segment (source's and destination's) and the
    geometric normals at its ends: near 0 the segment grazes a surface, and ray offsets (which
    side of a surface a ray starts on) decide J there, not the shift's mapping."""
    c = float(1.0)
    for side in range(2):
        y = xr
        if side == 1:
            y = yr
        d = target
        if kind != RC_ENV:
            seg = segment(y.hit.p, y.hit.ng, target)
            d = wp.vec3(seg[0], seg[1], seg[2])
            c = wp.min(c, wp.abs(wp.dot(d, surface_at(scene, tri, 0.3, 0.3, 0.0).ng)))
        c = wp.min(c, wp.abs(wp.dot(d, y.hit.ng)))
    return c


def make_fd_kernel(shift, replay_prefix):
    @wp.kernel(module="unique")
    def fd_kernel(scene: SceneDevice, params: PathReuseParams, gb: GBuffer, reservoirs: wp.array(dtype=PathReservoir),
                  partner: wp.array(dtype=int), out: wp.array2d(dtype=float)):
        i = wp.tid()
        for col in range(N_OUT):
            out[i, col] = 0.0
        r = reservoirs[i]
        if not holds_path(r) or r.W <= 0.0:
            return
        rcl = rc_length(r.flags)
        if rcl == NO_RC:
            return
        kind = rc_kind(r.flags)
        x0 = load_shading(scene, gb, i)
        y0 = load_shading(scene, gb, partner[i])
        if x0.valid == 0 or y0.valid == 0:
            return
        # rcPrev on both sides: the replayed prefix (the identity in PSS)
        xr = replay_prefix(scene, params, x0, r.seed, rcl - 1)
        yr = replay_prefix(scene, params, y0, r.seed, rcl - 1)
        if xr.valid == 0 or yr.valid == 0:
            return
        t = shift(scene, r, domain_at(y0, params))
        if t.valid == 0:
            return
        # ---- block at rcPrev: u -> z(u) -> u'
        lobe_prev = lobe_at_rc_prev(r.flags)
        ul = rng_uniform(r.seed, bounce_dim(rcl - 1, DIM_BSDF_LOBE))
        u0 = rng_uniform2(r.seed, bounce_dim(rcl - 1, DIM_BSDF_DIR))
        base = target_from(scene, xr, ul, u0, lobe_prev, kind, r.rc_tri)
        if base.ok == 0:
            return
        z_err = float(0.0)
        if kind == RC_ENV:
            z_err = wp.length(base.p - r.rc_wi)
        else:
            z_err = wp.length(base.p - surface_at(scene, r.rc_tri, r.rc_bary[0], r.rc_bary[1], 0.0).p)
        A = wp.mat22(0.0, 0.0, 0.0, 0.0)
        for k in range(2):
            c = richardson(column_at_rc_prev(scene, xr, yr, ul, u0, k, H, lobe_prev, kind, r.rc_tri),
                           column_at_rc_prev(scene, xr, yr, ul, u0, k, 0.5 * H, lobe_prev, kind, r.rc_tri))
            if c[2] == 0.0:
                return
            A[0, k] = c[0]
            A[1, k] = c[1]
        J = wp.abs(wp.determinant(A)) * lobe_probability(yr.mat, yr.wi, lobe_prev) / lobe_probability(
            xr.mat, xr.wi, lobe_prev)
        # ---- block at z, when z scatters on toward w_o: u -> w_o(u) -> u'
        z_factor = kind == RC_SURFACE and not (ends_with_nee(r.flags) != 0 and path_length(r.flags) == rcl)
        mat_z_kind = int(-1)
        if kind == RC_SURFACE:
            z = surface_at(scene, r.rc_tri, r.rc_bary[0], r.rc_bary[1], 0.0)
            mat_z = textured_material(scene, z.tri, z.uv)  # (no bump maps in its scenes)
            mat_z_kind = mat_z.kind
            if z_factor:
                fz = frame_from_normal(z.ns)
                s_src = segment(xr.hit.p, xr.hit.ng, z.p)
                s_dst = segment(yr.hit.p, yr.hit.ng, z.p)
                wi_src = to_local(fz, -wp.vec3(s_src[0], s_src[1], s_src[2]))
                wi_dst = to_local(fz, -wp.vec3(s_dst[0], s_dst[1], s_dst[2]))
                lobe_z = lobe_at_rc(r.flags)
                ulz = rng_uniform(r.seed, bounce_dim(rcl, DIM_BSDF_LOBE))
                uz = rng_uniform2(r.seed, bounce_dim(rcl, DIM_BSDF_DIR))
                D = wp.mat22(0.0, 0.0, 0.0, 0.0)
                for k in range(2):
                    c = richardson(column_at_z(mat_z, wi_src, wi_dst, ulz, uz, k, H, lobe_z),
                                   column_at_z(mat_z, wi_src, wi_dst, ulz, uz, k, 0.5 * H, lobe_z))
                    if c[2] == 0.0:
                        return
                    D[0, k] = c[0]
                    D[1, k] = c[1]
                J = J * wp.abs(wp.determinant(D)) * lobe_probability(mat_z, wi_dst, lobe_z) / lobe_probability(
                    mat_z, wi_src, lobe_z)
        out[i, 0] = 1.0
        out[i, 1] = t.J
        out[i, 2] = J
        out[i, 3] = float(rcl)
        out[i, 4] = float(kind)
        out[i, 5] = wp.where(z_factor, 1.0, 0.0)
        out[i, 6] = float(mat_z_kind)
        out[i, 7] = float(yr.mat.kind)
        out[i, 8] = z_err
        out[i, 9] = grazing_cos(scene, xr, yr, base.p, kind, r.rc_tri)
    return fd_kernel


_fd_kernels = {}


def fd_kernel(mutation="none"):
    if mutation not in _fd_kernels:
        shift = shift_path if mutation == "none" else make_shift(mutation)
        _fd_kernels[mutation] = make_fd_kernel(shift, _replay_prefixes[mutation])
    return _fd_kernels[mutation]


def run_fd(integ, params, gb, reservoirs, mutation="none", offset=(5, 3)):
    """The finite-difference kernel over every pixel with partner (x + dx, y + dy): domains from
    `gb` (primary hits; for suffixes, prefix ends), paths `reservoirs`; the rows of shifted paths."""
    n, w, h = integ.num_pixels, integ.width, integ.height
    idx = np.arange(n)
    x, y = idx % w, idx // w
    dx, dy = offset
    partner = (np.where(y + dy < h, y + dy, y - dy) * w + np.where(x + dx < w, x + dx, x - dx)).astype(np.int32)
    out = wp.zeros((n, N_OUT), dtype=float, device=integ.device)
    wp.launch(fd_kernel(mutation), dim=n, device=integ.device,
              inputs=[integ.dscene.scene, params, gb, reservoirs, wp.array(partner, dtype=int, device=integ.device), out])
    o = out.numpy()
    return o[o[:, 0] > 0]


GRAZING = 0.02     # the smallest |cos| at a reconnection segment's ends that is compared


J_RANGE = (1e-4, 1e4)  # the finite-difference J compared: outside, float32 differences of u' lose the digits


def well_conditioned(o):
    """The paths compared: no grazing reconnection segment, J within J_RANGE (counted, not hidden:
    the tests print how many were left out)."""
    return o[(o[:, 9] >= GRAZING) & (o[:, 2] >= J_RANGE[0]) & (o[:, 2] <= J_RANGE[1])]


def relative_errors(o):
    return np.abs(o[:, 1] - o[:, 2]) / o[:, 1]


def describe(name, shift, o, rel):
    kinds = {0: "surface", 1: "emitter", 2: "environment"}
    parts = [f"{name} {shift}: {len(o)} shifted paths, J {o[:, 1].min():.3g}..{o[:, 1].max():.3g}, relative error "
             f"median {np.median(rel):.2e}, 99th percentile {np.percentile(rel, 99):.2e}"]
    for rcl in sorted(set(o[:, 3].astype(int))):
        parts.append(f"rc at x{rcl + 1}: {(o[:, 3] == rcl).sum()}")
    for k, label in kinds.items():
        parts.append(f"z {label}: {(o[:, 4] == k).sum()}")
    parts.append(f"with a z factor: {int(o[:, 5].sum())}")
    return "; ".join(parts)


_round_trip_kernels = {}


def round_trip_kernel(mutation: str = "none", inlined: bool = False):
    """The test kernel over the shipped shift (its out-of-line build, or with `inlined` the build
    the temporal and spatial passes call), or over a mutant's
    (docs/validation.md#power-checks-the-mutation-table)."""
    key = (mutation, inlined)
    if key not in _round_trip_kernels:  # make_shift returns the shipped builds for "none"
        _round_trip_kernels[key] = make_round_trip_kernel(make_shift(mutation, inline=inlined))
    return _round_trip_kernels[key]


def make_round_trip_kernel(shift_path):
    @wp.kernel(module="unique")
    def round_trip_kernel(scene: SceneDevice, params: PathReuseParams, gb: GBuffer, reservoirs: wp.array(dtype=PathReservoir),
                            partner: wp.array(dtype=int), out: wp.array2d(dtype=float)):
        """Per pixel: [holds, rc length, F lum, identity valid, identity F lum, identity J, forward valid,
        back valid, back F lum, J product, forward J]."""
        pixel = wp.tid()
        r = reservoirs[pixel]
        for i in range(11):
            out[pixel, i] = 0.0
        sc = load_shading(scene, gb, pixel)
        if not holds_path(r) or sc.valid == 0 or r.W <= 0.0:
            return
        out[pixel, 0] = 1.0
        out[pixel, 1] = float(rc_length(r.flags))
        out[pixel, 2] = wp.dot(r.F, wp.vec3(0.2126, 0.7152, 0.0722))
        idn = shift_path(scene, r, domain_at(sc, params))
        out[pixel, 3] = float(idn.valid)
        out[pixel, 4] = wp.dot(idn.r.F, wp.vec3(0.2126, 0.7152, 0.0722))
        out[pixel, 5] = idn.J
        n = partner[pixel]
        sn = load_shading(scene, gb, n)
        fwd = shift_path(scene, r, domain_at(sn, params))
        out[pixel, 6] = float(fwd.valid)
        if fwd.valid != 0:
            back = shift_path(scene, fwd.r, domain_at(sc, params))
            out[pixel, 7] = float(back.valid)
            out[pixel, 8] = wp.dot(back.r.F, wp.vec3(0.2126, 0.7152, 0.0722))
            out[pixel, 9] = fwd.J * back.J
            out[pixel, 10] = fwd.J
    return round_trip_kernel


def run_round_trips(integ, p, gb, res, offset=3, mutation="none", inlined=False):
    """The round-trip kernel over every pixel of `integ` with partner pixel (x + offset, y):
    domains from the G-buffer `gb` (primary hits; for suffixes, the prefix ends), paths `res`."""
    n = integ.num_pixels
    w = integ.width
    idx = np.arange(n)
    x, y = idx % w, idx // w
    partner = (y * w + np.where(x + offset < w, x + offset, x - offset)).astype(np.int32)
    out = wp.zeros((n, 11), dtype=float, device=integ.device)
    wp.launch(round_trip_kernel(mutation, inlined), dim=n, inputs=[integ.dscene.scene, p, gb, res,
                                                 wp.array(partner, dtype=int, device=integ.device), out],
              device=integ.device)
    return out.numpy()


def rel(a, b):
    return np.abs(a - b) / np.maximum(np.abs(b), 1e-30)


def assert_identity_and_round_trip(o, shift, label, min_success=0.2):
    """D2 and D3 on the round-trip kernel's output (at most 0.2% failures each); forward shifts
    must succeed for at least `min_success` of the paths."""
    holds = o[:, 0] > 0
    assert holds.sum() > 200, "too few pixels hold a path"
    # D2: identity
    ident = o[holds]
    bad_valid = ident[:, 3] == 0
    bad = bad_valid | (rel(ident[:, 4], ident[:, 2]) > 1e-3) | (np.abs(ident[:, 5] - 1) > 1e-3)
    print(label, "paths", holds.sum(), "identity failures", bad.sum(),
          "rc lengths", np.unique(ident[:, 1], return_counts=True))
    assert bad.sum() <= max(1, 0.002 * holds.sum())
    # D3: round trips of successful forward shifts
    fwd = ident[:, 6] > 0
    assert fwd.mean() > min_success, f"shift success rate {fwd.mean():.3f}: reuse nearly dead"
    t = ident[fwd]
    bad = (t[:, 7] == 0) | (rel(t[:, 8], t[:, 2]) > 1e-3) | (np.abs(t[:, 9] - 1) > 1e-3)
    print("forward success", fwd.mean(), "round-trip failures", bad.sum(), "of", fwd.sum(),
          "J range", t[:, 10].min(), t[:, 10].max())
    assert bad.sum() <= max(1, 0.002 * fwd.sum())
    if shift == "replay":
        np.testing.assert_array_equal(t[:, 10], 1.0)
    else:
        assert np.std(np.log(t[:, 10])) > 1e-3, "reconnection Jacobians are all 1: not exercised"
