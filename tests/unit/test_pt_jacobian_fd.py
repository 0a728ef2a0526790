"""D5 (TESTING.md 5.3): the reconnection shift's analytic Jacobian against a finite-difference
Jacobian of the shift in primary sample space, on diffuse primary hits of the Cornell box.

A source path at pixel i scatters at its primary hit x with the two numbers u (cosine-weighted
hemisphere sampling, the diffuse lobe's), reaches z = trace(x, S(u)) and ends with NEE at z (no
pdf factor at z). Reconnected at pixel j's primary hit y, the destination direction y -> z has the
primary-sample coordinates u' = S^-1(direction) at y. The PSS Jacobian is |det du'/du|, taken here
by central differences of that map (ray tracing and the inverse warp only), and compared with the
J that the production shift (`shift_path`) returns. Its source terms come from the shift itself
(the path shifted into its own domain), so nothing of the formula is re-implemented here. Pixels
where a perturbed ray hits another triangle are skipped. Tolerances (float32): median relative
error < 1e-2, 90th percentile < 5e-2.
"""
import numpy as np
import warp as wp

import restir
from restir.api import make_integrator
from restir.device.intersect import T_MAX, SurfaceHit, offset_origin, trace_closest
from restir.device.sampling import cosine_hemisphere_to_square, square_to_cosine_hemisphere, to_local, to_world
from restir.device.scene_device import SceneDevice
from restir.device.types import LOBE_DIFFUSE_REFLECTION, MAT_DIFFUSE
from restir.integrators.common.gbuffer import GBuffer
from restir.integrators.common.shading import Shading, load_shading
from restir.integrators.restir_pt.params import PTRParams
from restir.integrators.restir_pt.path_sample import RC_SURFACE, PathReservoir, pack_flags
from restir.integrators.restir_pt.rc_criteria import segment
from restir.integrators.restir_pt.shift import shift_path

H = 1.0e-3


@wp.func
def hit_from(scene: SceneDevice, x: Shading, u: wp.vec2) -> SurfaceHit:
    """The vertex z reached from x with the sample u (a miss: valid = 0)."""
    d = wp.normalize(to_world(x.frame, square_to_cosine_hemisphere(u)))
    return trace_closest(scene, offset_origin(x.hit.p, x.hit.ng, d), d, T_MAX)


@wp.func
def u_at(y: Shading, z: wp.vec3) -> wp.vec2:
    seg = segment(y.hit.p, y.hit.ng, z)
    return cosine_hemisphere_to_square(to_local(y.frame, wp.vec3(seg[0], seg[1], seg[2])))


@wp.kernel
def fd_kernel(scene: SceneDevice, params: PTRParams, gb: GBuffer, partner: wp.array(dtype=int),
              u0: wp.array(dtype=wp.vec2), out: wp.array(dtype=wp.vec2)):
    i = wp.tid()
    out[i] = wp.vec2(0.0)
    x = load_shading(scene, gb, i)
    y = load_shading(scene, gb, partner[i])
    if x.valid == 0 or y.valid == 0 or x.mat.kind != MAT_DIFFUSE or y.mat.kind != MAT_DIFFUSE:
        return
    z = hit_from(scene, x, u0[i])
    if z.valid == 0:
        return
    # the source path: rc vertex z at length 1, NEE at z (a fixed light direction and radiance)
    r = PathReservoir()
    r.flags = pack_flags(1, 1, LOBE_DIFFUSE_REFLECTION, 0, 1, RC_SURFACE)
    r.rc_tri = z.tri
    r.rc_bary = z.bary
    r.rc_wi = wp.normalize(-to_world(x.frame, square_to_cosine_hemisphere(u0[i])) + wp.vec3(0.0, 0.3, 0.0))
    r.rc_L = wp.vec3(1.0)
    r.light_pdf = 1.0
    r.rc_jac = wp.vec2(1.0, 1.0)
    r.W = 1.0
    r.M = 1.0
    own = shift_path(scene, params, r, x)   # the source terms, as the shift computes them
    if own.valid == 0:
        return
    r.rc_jac = own.r.rc_jac
    t = shift_path(scene, params, r, y)
    if t.valid == 0:
        return
    # central differences of u -> u'
    cols = wp.mat22(0.0, 0.0, 0.0, 0.0)
    for k in range(2):
        e = wp.vec2(0.0)
        e[k] = H
        a = hit_from(scene, x, u0[i] + e)
        b = hit_from(scene, x, u0[i] - e)
        if a.valid == 0 or b.valid == 0 or a.tri != z.tri or b.tri != z.tri:
            return
        dk = (u_at(y, a.p) - u_at(y, b.p)) / (2.0 * H)
        cols[0, k] = dk[0]
        cols[1, k] = dk[1]
    out[i] = wp.vec2(t.J, wp.abs(wp.determinant(cols)))


def test_reconnection_jacobian_matches_finite_differences():
    scene = restir.load_scene("builtin:cornell-box", width=64, height=64)
    cfg = restir.RenderConfig(method="restir-pt", spp=1, max_depth=4, seed=5,
                              settings={"shift": "reconnection", "direct": "pt", "temporal": False,
                                        "spatial.rounds": 0})
    integ = make_integrator(scene, cfg)
    integ.render_frame(0)
    n, w = integ.num_pixels, integ.width
    idx = np.arange(n)
    x, yy = idx % w, idx // w
    partner = (np.clip(yy + 3, 0, w - 1) * w + np.where(x + 5 < w, x + 5, x - 5)).astype(np.int32)
    rng = np.random.default_rng(3)
    u0 = rng.uniform(0.02, 0.98, (n, 2)).astype(np.float32)
    out = wp.zeros(n, dtype=wp.vec2, device=integ.device)
    wp.launch(fd_kernel, dim=n, inputs=[integ.dscene.scene, integ.params(0, 0), integ.gbuffers.previous,
                                         wp.array(partner, dtype=int, device=integ.device),
                                         wp.array(u0, dtype=wp.vec2, device=integ.device), out], device=integ.device)
    o = out.numpy()
    ok = o[:, 0] > 0
    rel = np.abs(o[ok, 0] - o[ok, 1]) / o[ok, 1]
    print(f"{ok.sum()} paths; J range {o[ok, 0].min():.3g}..{o[ok, 0].max():.3g}; relative error median "
          f"{np.median(rel):.2e}, 90th percentile {np.percentile(rel, 90):.2e}")
    assert ok.sum() > 500
    assert np.std(np.log(o[ok, 0])) > 0.1  # the Jacobians vary: the test is not about J = 1
    assert np.median(rel) < 1e-2 and np.percentile(rel, 90) < 5e-2
