"""The stored ReSTIR DI reservoir and the integrand it is resampled by.

A sample y is a point on an emissive triangle (area measure), a direction toward the
environment (solid-angle measure) or a delta light (a point or a direction: counting measure,
device/delta_lights.py), so moving it to another pixel's primary hit is the identity in its
measure (J = 1). The integrand at a primary hit x (smooth BSDF lobes only):

    f_x(y) = f_s(x, wo, w_y) * Le(y -> x) * G(x, y) * V(x, y),   G = |cos theta_y| / d^2 (1 for env)

and for a delta light f_s * (I falloff / d^2, or E) * V: no cosine at the light, no area measure.

`unshadowed_contribution` is f_x without V. The target p_hat is its luminance, times V when
targets are visibility-aware (setting `visibility = reuse`; see docs/guide/restir_di.md).
"""
import warp as wp

from ...device.bsdf import bsdf_eval, bsdf_pdf
from ...device.color import luminance
from ...device.delta_lights import delta_arrival, delta_light_index, is_delta_light
from ...device.intersect import SurfaceHit, T_MAX, surface_at, visible_to_light
from ...device.lights import delta_light_probability, env_eval, env_pdf, triangle_emission
from ...device.sampling import to_local
from ...device.scene_device import SceneDevice
from ...device.types import DELTA_DIRECTIONAL, LIGHT_ENV, LIGHT_NONE
from ...resampling.ris import ReservoirWeights
from ..common.shading import Shading


@wp.struct
class DIReservoir:
    """24 bytes: a triangle sample is kept as its barycentrics (the point and its normals are
    rebuilt by surface_at, bit for bit those the candidate was evaluated with), an environment
    sample as its direction."""
    light_tri: int      # emissive triangle, LIGHT_ENV: environment, a delta light's identity, LIGHT_NONE: no sample
    light_y: wp.vec3    # (bu, bv, 0): barycentrics on the triangle (surface_at's), or the unit direction (unused
                        # for a delta light)
    W: float            # unbiased contribution weight, in the sample's measure
    M: float            # confidence


@wp.struct
class LightPoint:
    """A reservoir's sample, decoded: the light point (or the environment direction), its
    geometric normal (area measure) and its shading normal (decides the emitting side); for a
    delta light, its position (n = 0: no surface to offset the shadow ray from)."""
    y: wp.vec3
    n: wp.vec3
    ns: wp.vec3


@wp.func
def light_point(scene: SceneDevice, r: DIReservoir) -> LightPoint:
    lp = LightPoint()
    if r.light_tri == LIGHT_ENV:
        lp.y = r.light_y
    elif is_delta_light(r.light_tri):
        lp.y = scene.delta_lights[delta_light_index(r.light_tri)].p
    elif r.light_tri != LIGHT_NONE:
        h = surface_at(scene, r.light_tri, r.light_y[0], r.light_y[1], 0.0)
        lp.y = h.p
        lp.n = h.ng
        lp.ns = h.ns
    return lp


@wp.func
def on_triangle(tri: int, bary: wp.vec2) -> DIReservoir:
    """A sample on emissive triangle tri at surface_at's barycentrics (no weights yet)."""
    r = empty_reservoir()
    r.light_tri = tri
    r.light_y = wp.vec3(bary[0], bary[1], 0.0)
    return r


@wp.func
def empty_reservoir() -> DIReservoir:
    r = DIReservoir()
    r.light_tri = LIGHT_NONE
    r.W = 0.0
    r.M = 0.0
    return r


@wp.func
def store(chosen: DIReservoir, f: ReservoirWeights) -> DIReservoir:
    """The stored result of a resampling pass: the chosen input's sample with the pass's W and M
    (the one field copy of every DI stage); with nothing selected, no sample but the confidence."""
    r = chosen
    r.W = f.W
    r.M = f.M
    if f.selected == 0:
        r.light_tri = LIGHT_NONE
    return r


@wp.func
def at_infinity(scene: SceneDevice, light: int) -> bool:
    """The light is the environment or a directional light (an unbounded shadow ray)."""
    if light == LIGHT_ENV:
        return True
    return is_delta_light(light) and scene.delta_lights[delta_light_index(light)].kind == DELTA_DIRECTIONAL


@wp.func
def direction_to_light(scene: SceneDevice, r: DIReservoir, lp: LightPoint, x: wp.vec3) -> wp.vec4:
    """(unit direction x -> y, distance); distance T_MAX for the environment and a directional light."""
    if r.light_tri == LIGHT_ENV:
        return wp.vec4(lp.y[0], lp.y[1], lp.y[2], T_MAX)
    if at_infinity(scene, r.light_tri):
        a = scene.delta_lights[delta_light_index(r.light_tri)].axis
        return wp.vec4(-a[0], -a[1], -a[2], T_MAX)
    d = lp.y - x
    dist = wp.length(d)
    if dist <= 0.0:
        return wp.vec4(0.0, 0.0, 1.0, 0.0)
    d = d / dist
    return wp.vec4(d[0], d[1], d[2], dist)


@wp.func
def unshadowed_contribution(scene: SceneDevice, sh: Shading, r: DIReservoir) -> wp.vec3:
    """f_s * Le * G at the primary hit sh (no visibility); 0 for no sample."""
    if r.light_tri == LIGHT_NONE:
        return wp.vec3(0.0)
    lp = light_point(scene, r)
    dd = direction_to_light(scene, r, lp, sh.hit.p)
    d = wp.vec3(dd[0], dd[1], dd[2])
    if dd[3] <= 0.0:
        return wp.vec3(0.0)
    Le = wp.vec3(0.0)
    G = float(1.0)
    if r.light_tri == LIGHT_ENV:
        Le = env_eval(scene, d)
    elif is_delta_light(r.light_tri):
        Le = delta_arrival(scene.delta_lights[delta_light_index(r.light_tri)], sh.hit.p).Le
    else:
        Le = triangle_emission(scene, r.light_tri, lp.ns, -d)
        G = wp.abs(wp.dot(lp.n, d)) / (dd[3] * dd[3])
    f = bsdf_eval(sh.mat, sh.wi, to_local(sh.frame, d))
    return wp.cw_mul(f, Le) * G


@wp.func
def light_visible(scene: SceneDevice, hit: SurfaceHit, r: DIReservoir) -> bool:
    lp = light_point(scene, r)
    dd = direction_to_light(scene, r, lp, hit.p)
    infinite = wp.where(at_infinity(scene, r.light_tri), 1, 0)
    return visible_to_light(scene, hit.p, hit.ng, wp.vec3(dd[0], dd[1], dd[2]), lp.y, lp.n, infinite)


@wp.func
def target(scene: SceneDevice, sh: Shading, r: DIReservoir, visibility: int) -> wp.vec2:
    """(p_hat_x(y), shadow rays traced) for r's sample y at the primary hit sh.

    With visibility-aware targets a ray is traced only when it can matter: a sample with W = 0
    enters every weight multiplied by its W, so its target is reported as 0 without a ray.
    """
    p = luminance(unshadowed_contribution(scene, sh, r))
    if visibility == 0 or p <= 0.0:
        return wp.vec2(p, 0.0)
    if r.W <= 0.0:
        return wp.vec2(0.0, 0.0)
    if light_visible(scene, sh.hit, r):
        return wp.vec2(p, 1.0)
    return wp.vec2(0.0, 1.0)


@wp.func
def own_target(scene: SceneDevice, sh: Shading, r: DIReservoir, visibility: int) -> float:
    """p_hat of a stored reservoir's sample at the primary hit of the pixel that stores it.

    With visibility-aware targets W > 0 implies V = 1 there (the sample survived the visibility
    stage or was selected with a visibility-aware target in that domain), so no ray is needed.
    """
    p = luminance(unshadowed_contribution(scene, sh, r))
    if visibility != 0 and r.W <= 0.0:
        return 0.0
    return p


@wp.func
def light_jacobian(dst: SceneDevice, src: SceneDevice, r: DIReservoir) -> float:
    """|J| of moving r's sample from the scene `src` to the scene `dst` (a frame before and after
    the scene moved): a triangle sample keeps its barycentrics, so its area measure changes by its
    triangle's area ratio (1 under rigid motion, exactly 1 when nothing moved); a direction or a
    delta light keeps its measure (1)."""
    if r.light_tri < 0:
        return 1.0
    i = 3 * r.light_tri
    a_dst = wp.length(wp.cross(dst.positions[i + 1] - dst.positions[i], dst.positions[i + 2] - dst.positions[i]))
    a_src = wp.length(wp.cross(src.positions[i + 1] - src.positions[i], src.positions[i + 2] - src.positions[i]))
    if a_src <= 0.0:
        return 0.0
    return a_dst / a_src


@wp.func
def candidate_densities(scene: SceneDevice, sh: Shading, r: DIReservoir, with_bsdf: int) -> wp.vec2:
    """(p_L(y), p_B(y)): the densities with which light sampling and BSDF sampling at sh produce
    r's sample y, both in y's measure (area on a triangle, solid angle toward the environment,
    a probability for a delta light, which BSDF sampling never produces: p_B = 0).
    p_B omits V(x, y); why that is sound only with visibility-aware reuse: docs/guide/restir_di.md."""
    lp = light_point(scene, r)
    dd = direction_to_light(scene, r, lp, sh.hit.p)
    d = wp.vec3(dd[0], dd[1], dd[2])
    if r.light_tri == LIGHT_NONE or dd[3] <= 0.0:
        return wp.vec2(0.0, 0.0)
    if is_delta_light(r.light_tri):
        return wp.vec2(delta_light_probability(scene, r.light_tri), 0.0)
    p_L = float(0.0)
    to_measure = float(1.0)  # solid angle -> y's measure
    if r.light_tri == LIGHT_ENV:
        p_L = env_pdf(scene, d)
    else:
        p_L = (1.0 - scene.env_select_prob) * scene.tri_light_pdf[r.light_tri]
        to_measure = wp.abs(wp.dot(lp.n, d)) / (dd[3] * dd[3])
    p_B = float(0.0)
    if with_bsdf != 0:
        p_B = bsdf_pdf(sh.mat, sh.wi, to_local(sh.frame, d)) * to_measure
    return wp.vec2(p_L, p_B)
