"""Light sampling (NEE) and emission lookup for area emitters, delta lights and the environment.

The environment (constant or lat-long map, Mitsuba's mapping) is chosen with env_select_prob;
otherwise one alias table chooses among the emissive triangles and the delta lights in
proportion to power (scene/upload.py). Area emitters: then a point uniformly by area; the
density is converted to solid angle at the shading point. Delta lights (delta_lights.py): the
sample's `pdf` is the light's selection probability, a probability in the light's own delta
measure, and `Le` what it sends toward the point; BSDF sampling never finds one, so its MIS
weight is 1.
"""
import warp as wp

from .delta_lights import delta_arrival, delta_light_index, is_delta_light
from .intersect import surface_at
from .sampling import sample_alias, sample_cdf, square_to_uniform_sphere, square_to_uniform_triangle
from .scene_device import SceneDevice
from .types import DELTA_DIRECTIONAL, ENV_CONSTANT, ENV_MAP, ENV_NONE, INV_FOUR_PI, LIGHT_ENV, PI


@wp.struct
class LightSample:
    wi: wp.vec3      # unit direction from the shading point toward the light
    dist: float      # distance to the light point (T_MAX-like for the environment)
    p: wp.vec3       # light point (surface lights)
    bary: wp.vec2    # its barycentrics in surface_at's convention: (tri, bary) reproduces p, n, ns exactly
    n: wp.vec3       # geometric normal at the light point
    ns: wp.vec3      # shading normal at the light point (decides the emitting side)
    tri: int         # emissive triangle, LIGHT_ENV for the environment, a delta light's identity
    Le: wp.vec3      # emitted radiance toward the shading point (a delta light's: delta_lights.py)
    pdf: float       # solid-angle density, selection probability included (a delta light: that
                     # probability alone); 0 = failed
    is_env: int
    is_delta: int    # a delta light: reached by light sampling only (MIS weight 1)
    infinite: int    # the light is at infinity (the environment, a directional light): an unbounded shadow ray


# ----------------------------------------------------------------------------- environment
@wp.func
def env_dir_to_uv(scene: SceneDevice, d_world: wp.vec3) -> wp.vec2:
    v = scene.env_to_local * d_world
    u = wp.atan2(v[0], -v[2]) * (0.5 / PI)
    u = u - wp.floor(u)
    t = wp.acos(wp.clamp(v[1], -1.0, 1.0)) / PI
    return wp.vec2(u, t)


@wp.func
def env_uv_to_dir(scene: SceneDevice, uv: wp.vec2) -> wp.vec3:
    phi = 2.0 * PI * uv[0]
    theta = PI * uv[1]
    st = wp.sin(theta)
    v = wp.vec3(st * wp.sin(phi), wp.cos(theta), -st * wp.cos(phi))
    return scene.env_to_world * v


@wp.func
def env_pixel(scene: SceneDevice, uv: wp.vec2) -> int:
    x = wp.min(int(uv[0] * float(scene.env_width)), scene.env_width - 1)
    y = wp.min(int(uv[1] * float(scene.env_height)), scene.env_height - 1)
    return y * scene.env_width + x


@wp.func
def env_texel(scene: SceneDevice, x: int, y: int) -> wp.vec3:
    return scene.env_pixels[y * scene.env_width + (x % scene.env_width)]


@wp.func
def env_lookup(scene: SceneDevice, uv: wp.vec2) -> wp.vec3:
    """Mitsuba's envmap lookup: bilinear; columns periodic with texel centres at (i + 1/2)/W,
    rows at v = j / (H - 1) (the first and last rows sit on the poles)."""
    w = scene.env_width
    h = scene.env_height
    u = uv[0] - 0.5 / float(w)
    u = (u - wp.floor(u)) * float(w)
    v = uv[1] * float(h - 1)
    x0 = wp.min(int(u), w - 1)
    y0 = wp.min(int(v), h - 2)
    fx = u - float(x0)
    fy = v - float(y0)
    a = env_texel(scene, x0, y0) * (1.0 - fx) + env_texel(scene, x0 + 1, y0) * fx
    b = env_texel(scene, x0, y0 + 1) * (1.0 - fx) + env_texel(scene, x0 + 1, y0 + 1) * fx
    return a * (1.0 - fy) + b * fy


@wp.func
def env_eval(scene: SceneDevice, d_world: wp.vec3) -> wp.vec3:
    if scene.env_kind == ENV_CONSTANT:
        return scene.env_radiance
    if scene.env_kind == ENV_MAP:
        return wp.cw_mul(env_lookup(scene, env_dir_to_uv(scene, d_world)), scene.env_radiance)
    return wp.vec3(0.0)


@wp.func
def env_pdf(scene: SceneDevice, d_world: wp.vec3) -> float:
    """Solid-angle density of env sampling, selection probability included."""
    if scene.env_kind == ENV_CONSTANT:
        return scene.env_select_prob * INV_FOUR_PI
    if scene.env_kind == ENV_MAP:
        uv = env_dir_to_uv(scene, d_world)
        i = env_pixel(scene, uv)
        y = i // scene.env_width
        x = i - y * scene.env_width
        row = y * (scene.env_width + 1)
        p_row = scene.env_marginal_cdf[y + 1] - scene.env_marginal_cdf[y]
        p_col = scene.env_conditional_cdf[row + x + 1] - scene.env_conditional_cdf[row + x]
        st = wp.sin(PI * uv[1])
        if st <= 0.0:
            return 0.0
        pdf_uv = p_row * p_col * float(scene.env_width * scene.env_height)
        return scene.env_select_prob * pdf_uv / (2.0 * PI * PI * st)
    return 0.0


@wp.func
def sample_env(scene: SceneDevice, u: wp.vec2) -> LightSample:
    ls = LightSample()
    ls.is_env = 1
    ls.infinite = 1
    ls.tri = LIGHT_ENV
    ls.dist = 1.0e30
    ls.pdf = 0.0
    if scene.env_kind == ENV_CONSTANT:
        ls.wi = square_to_uniform_sphere(u)
    elif scene.env_kind == ENV_MAP:
        y = sample_cdf(scene.env_marginal_cdf, 0, scene.env_height, u[1])
        y0 = scene.env_marginal_cdf[y]
        y1 = scene.env_marginal_cdf[y + 1]
        fy = (u[1] - y0) / wp.max(y1 - y0, 1.0e-30)
        row = y * (scene.env_width + 1)
        x = sample_cdf(scene.env_conditional_cdf, row, scene.env_width, u[0])
        x0 = scene.env_conditional_cdf[row + x]
        x1 = scene.env_conditional_cdf[row + x + 1]
        fx = (u[0] - x0) / wp.max(x1 - x0, 1.0e-30)
        uv = wp.vec2((float(x) + wp.clamp(fx, 0.0, 0.999999)) / float(scene.env_width),
                     (float(y) + wp.clamp(fy, 0.0, 0.999999)) / float(scene.env_height))
        ls.wi = env_uv_to_dir(scene, uv)
    else:
        return ls
    ls.Le = env_eval(scene, ls.wi)
    ls.pdf = env_pdf(scene, ls.wi)
    return ls


# ----------------------------------------------------------------------------- area emitters
@wp.func
def triangle_emission(scene: SceneDevice, tri: int, ns: wp.vec3, w_out: wp.vec3) -> wp.vec3:
    """Radiance leaving emissive triangle `tri` toward w_out: on the front side of the shading
    normal, or on either side of a two-sided emitter."""
    if wp.dot(ns, w_out) <= 0.0:
        if scene.num_twosided_emitters == 0:
            return wp.vec3(0.0)
        if scene.tri_emit_twosided[tri] == 0:
            return wp.vec3(0.0)
    return scene.tri_emission[tri]


@wp.func
def triangle_light_pdf(scene: SceneDevice, tri: int, ng: wp.vec3, w_to_light: wp.vec3, dist: float) -> float:
    """Solid-angle density with which NEE from a point at `dist` samples this point of `tri`."""
    cos_l = wp.abs(wp.dot(ng, w_to_light))
    if cos_l <= 0.0:
        return 0.0
    return (1.0 - scene.env_select_prob) * scene.tri_light_pdf[tri] * dist * dist / cos_l


@wp.func
def sample_triangle_light(scene: SceneDevice, x: wp.vec3, tri: int, u: wp.vec2) -> LightSample:
    """A point uniformly by area on emissive triangle `tri` (already chosen)."""
    ls = LightSample()
    ls.pdf = 0.0
    ls.tri = tri
    b = square_to_uniform_triangle(u)  # weights of vertices 1 and 2
    # the point through surface_at, so that a sample stored as (tri, bary) is this point bit for bit
    h = surface_at(scene, tri, 1.0 - b[0] - b[1], b[0], 0.0)
    ls.p = h.p
    ls.bary = h.bary
    ls.n = h.ng
    ls.ns = h.ns
    d = ls.p - x
    dist = wp.length(d)
    if dist <= 0.0:
        return ls
    ls.wi = d / dist
    ls.dist = dist
    ls.Le = triangle_emission(scene, tri, ls.ns, -ls.wi)
    ls.pdf = triangle_light_pdf(scene, tri, ls.n, ls.wi, dist)
    return ls


# ----------------------------------------------------------------------------- delta lights
@wp.func
def delta_light_probability(scene: SceneDevice, light_id: int) -> float:
    """The probability that light sampling picks this delta light (its `pdf`: delta measure)."""
    return (1.0 - scene.env_select_prob) * scene.delta_light_pmf[delta_light_index(light_id)]


@wp.func
def sample_delta_light(scene: SceneDevice, x: wp.vec3, light_id: int) -> LightSample:
    """The connection from x to a delta light (already chosen): nothing left to sample."""
    ls = LightSample()
    ls.pdf = 0.0
    ls.tri = light_id
    ls.is_delta = 1
    l = scene.delta_lights[delta_light_index(light_id)]
    a = delta_arrival(l, x)
    if a.dist <= 0.0:
        return ls
    ls.infinite = wp.where(l.kind == DELTA_DIRECTIONAL, 1, 0)
    ls.wi = a.wi
    ls.dist = a.dist
    ls.p = l.p
    ls.Le = a.Le
    ls.pdf = delta_light_probability(scene, light_id)
    return ls


@wp.func
def sample_light(scene: SceneDevice, x: wp.vec3, u_sel: float, u: wp.vec2) -> LightSample:
    """One light sample for NEE. u_sel picks the environment or the alias table, and then the
    table's light (an emissive triangle or a delta light)."""
    num_lights = scene.num_tri_lights + scene.num_delta_lights
    if scene.env_kind != ENV_NONE and (num_lights == 0 or u_sel < scene.env_select_prob):
        return sample_env(scene, u)
    if num_lights == 0:
        ls = LightSample()
        ls.pdf = 0.0
        return ls
    u2 = wp.where(scene.env_kind != ENV_NONE, (u_sel - scene.env_select_prob) / (1.0 - scene.env_select_prob), u_sel)
    light_id = int(scene.light_tri[sample_alias(scene.light_prob, scene.light_alias, wp.min(u2, 0.99999994))])
    if is_delta_light(light_id):
        return sample_delta_light(scene, x, light_id)
    return sample_triangle_light(scene, x, light_id, u)
