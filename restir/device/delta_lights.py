"""Delta lights: a point light, a spot light and a directional light, as one record.

A delta light is a single point (point, spot) or a single direction (directional), so no ray
found by BSDF sampling ever reaches it: it is lit by light sampling alone, with MIS weight 1
(docs/theory/delta_lights.md). What it sends toward a shading point x is a value in the measure
of its own delta, which every estimator uses where an area light's radiance and geometry term
would be:

    point, spot:  I * falloff(cos theta) / |p - x|^2   (theta from the spot's axis; falloff 1 for a point)
    directional:  E                                     (irradiance on a surface facing the light)

so a light connection at x contributes f_s(x, wo, wi) |cos| * that / P(select the light), with no
cosine at the light and no area or solid-angle density.

The spot's falloff between its inner and outer cone is written for each format that defines
one, exactly (`falloff`): Mitsuba 3's is linear in the angle, pbrt-v4's a smoothstep in the
cosine, glTF's a linear ramp in the cosine, squared (with the 0.001 floor on the ramp's width
that KHR_lights_punctual's reference code uses).
"""
import warp as wp

from .types import DELTA_DIRECTIONAL, DELTA_SPOT, FALLOFF_LINEAR_ANGLE, FALLOFF_SMOOTHSTEP, LIGHT_DELTA_BASE

FAR_AWAY = wp.constant(1.0e30)  # the distance of a directional light (beyond every surface)


@wp.struct
class DeltaLight:
    kind: int          # DELTA_POINT, DELTA_SPOT, DELTA_DIRECTIONAL
    p: wp.vec3         # position (point, spot)
    axis: wp.vec3      # spot: the unit direction it shines along; directional: the direction light travels
    I: wp.vec3         # intensity (W/sr: point, spot) or irradiance (W/m^2: directional)
    falloff: int       # spot: FALLOFF_* (types.py)
    cos_inner: float   # spot: the cosine of the inner cone's half-angle (full intensity inside)
    cos_outer: float   # spot: the cosine of the outer cone's half-angle (dark outside)
    inner: float       # the same half-angles in radians (the linear-in-angle falloff)
    outer: float


@wp.struct
class DeltaArrival:
    """What a delta light sends toward a point x."""
    wi: wp.vec3    # unit direction from x toward the light
    dist: float    # distance to it (FAR_AWAY for a directional light)
    Le: wp.vec3    # I falloff / d^2, or E (see the module docstring)


@wp.func
def is_delta_light(light_id: int) -> bool:
    return light_id <= LIGHT_DELTA_BASE


@wp.func
def delta_light_index(light_id: int) -> int:
    return LIGHT_DELTA_BASE - light_id


@wp.func
def spot_falloff(l: DeltaLight, cos_theta: float) -> float:
    """The spot's falloff at angle theta from its axis, in [0, 1]."""
    if cos_theta <= l.cos_outer:
        return 0.0
    if l.falloff == FALLOFF_LINEAR_ANGLE:
        if cos_theta >= l.cos_inner:
            return 1.0
        return (l.outer - wp.acos(wp.min(cos_theta, 1.0))) / (l.outer - l.inner)
    if l.falloff == FALLOFF_SMOOTHSTEP:
        if cos_theta >= l.cos_inner:
            return 1.0
        t = (cos_theta - l.cos_outer) / (l.cos_inner - l.cos_outer)
        return t * t * (3.0 - 2.0 * t)
    # FALLOFF_SQUARED_RAMP: no early exit at the inner cone (the ramp's width has a floor)
    t = wp.clamp((cos_theta - l.cos_outer) / wp.max(0.001, l.cos_inner - l.cos_outer), 0.0, 1.0)
    return t * t


@wp.func
def delta_arrival(l: DeltaLight, x: wp.vec3) -> DeltaArrival:
    """What light l sends toward x; Le = 0 where it sends nothing (outside a spot's cone, or x on
    the light itself)."""
    a = DeltaArrival()
    if l.kind == DELTA_DIRECTIONAL:
        a.wi = -l.axis
        a.dist = FAR_AWAY
        a.Le = l.I
        return a
    d = l.p - x
    dist = wp.length(d)
    if dist <= 0.0:
        return a
    a.wi = d / dist
    a.dist = dist
    falloff = float(1.0)
    if l.kind == DELTA_SPOT:
        falloff = spot_falloff(l, -wp.dot(a.wi, l.axis))
    a.Le = l.I * (falloff / (dist * dist))
    return a
