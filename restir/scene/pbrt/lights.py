"""pbrt-v4's lights as restir's emitters.

Every pbrt-v4 light divides its spectrum by the spectrum's luminance and multiplies by `scale`
(spectra.py gives the colour at luminance 1; an `rgb` keeps its own), then by the target power
when `power` (or a distant or infinite light's `illuminance`) is given, as pbrt-v4 defines it:
a point light's 4 pi, a spot's 2 pi (1 - (cos_start + cos_end) / 2), an area light's pi A (2 pi A
two-sided), an infinite light's pi. The film's imaging ratio (camera.py) multiplies all of them.
A spot's falloff is pbrt-v4's smoothstep between the cones at `coneangle - conedeltaangle` and
`coneangle`.
"""
import math

import numpy as np

from ..errors import SceneError
from . import spectra
from .params import ParamSet

LIGHTS = ("point", "spot", "distant", "infinite")


def colour(ps: ParamSet, name: str, ratio: float) -> np.ndarray:
    spec = ps.spectrum(name) if ps.has(name) else ("rgb", np.ones(3))
    scale = ps.float("scale", 1.0)
    if scale < 0:
        raise SceneError("a light's scale must be non-negative", ps.loc_of("scale"))
    return spectra.emission(spec, ps.loc_of(name)) * scale * ratio


def _power(ps: ParamSet, name: str) -> float | None:
    v = ps.float(name, -1.0)
    return v if v > 0 else None


def light_source(kind: str, ps: ParamSet, ctm: np.ndarray, ratio: float) -> dict:
    """A LightSource directive as an emitter object (point, spot, directional, constant)."""
    if kind not in LIGHTS:
        raise SceneError(f"LightSource '{kind}' is not supported (supported: {', '.join(LIGHTS)})", ps.loc)
    if kind == "point":
        i = colour(ps, "I", ratio)
        phi = _power(ps, "power")
        if phi:
            i = i * phi / (4 * math.pi)
        pos = ctm[:3, :3] @ ps.point3("from", [0.0, 0.0, 0.0]) + ctm[:3, 3]
        out = {"type": "point", "position": pos, "intensity": i}
    elif kind == "spot":
        i = colour(ps, "I", ratio)
        cone = ps.float("coneangle", 30.0)
        delta = ps.float("conedeltaangle", 5.0)
        if not 0 < cone <= 180:
            raise SceneError("spot: coneangle must be in (0, 180] degrees", ps.loc_of("coneangle"))
        if not 0 <= delta <= cone:
            raise SceneError("spot: conedeltaangle must be in [0, coneangle]", ps.loc_of("conedeltaangle"))
        phi = _power(ps, "power")
        if phi:
            c_end, c_start = math.cos(math.radians(cone)), math.cos(math.radians(cone - delta))
            i = i * phi / (2 * math.pi * ((1 - c_start) + (c_start - c_end) / 2))
        p_from, p_to = ps.point3("from", [0.0, 0.0, 0.0]), ps.point3("to", [0.0, 0.0, 1.0])
        pos = ctm[:3, :3] @ p_from + ctm[:3, 3]
        axis = ctm[:3, :3] @ (p_to - p_from)
        if np.linalg.norm(axis) <= 0:
            raise SceneError("spot: 'from' and 'to' coincide", ps.loc)
        out = {"type": "spot", "to_world": _frame(axis / np.linalg.norm(axis), pos), "intensity": i,
               "cutoff_angle": cone, "beam_width": cone - delta, "falloff": "smoothstep"}
    elif kind == "distant":
        e = colour(ps, "L", ratio)
        ev = _power(ps, "illuminance")
        if ev:
            e = e * ev
        d = ctm[:3, :3] @ (ps.point3("to", [0.0, 0.0, 1.0]) - ps.point3("from", [0.0, 0.0, 0.0]))
        if np.linalg.norm(d) <= 0:
            raise SceneError("distant: 'from' and 'to' coincide", ps.loc)
        out = {"type": "directional", "direction": d / np.linalg.norm(d), "irradiance": e}
    else:
        if ps.has("filename"):
            raise SceneError("infinite: an image (equal-area environment map) is not supported yet; a constant "
                             "'L' is", ps.loc_of("filename"))
        if ps.has("portal"):
            raise SceneError("infinite: 'portal' is not supported", ps.loc_of("portal"))
        radiance = colour(ps, "L", ratio)
        ev = _power(ps, "illuminance")
        if ev:
            radiance = radiance * ev / math.pi
        out = {"type": "constant", "radiance": radiance}
    ps.warn_unused()
    out["_loc"] = ps.loc
    return out


class AreaLight:
    """An AreaLightSource "diffuse", read once; `emitter(area)` for each shape it lights (`power`
    needs the shape's world-space area)."""

    def __init__(self, kind: str, ps: ParamSet, ratio: float):
        if kind != "diffuse":
            raise SceneError(f"AreaLightSource '{kind}' is not supported (diffuse only)", ps.loc)
        if ps.bool("twosided", False):
            raise SceneError("AreaLightSource: 'twosided' emitters are not supported yet", ps.loc_of("twosided"))
        for p in ("filename", "alpha"):
            if ps.has(p):
                raise SceneError(f"AreaLightSource: '{p}' is not supported", ps.loc_of(p))
        self.loc = ps.loc
        self.radiance = colour(ps, "L", ratio)
        self.phi = _power(ps, "power")
        ps.warn_unused()

    def emitter(self, area: float | None) -> dict:
        radiance = self.radiance
        if self.phi:
            if not area:
                raise SceneError("AreaLightSource: 'power' on a shape whose area is zero", self.loc)
            radiance = radiance * self.phi / (math.pi * area)
        return {"type": "area", "radiance": radiance, "_loc": self.loc}


def _frame(z: np.ndarray, origin: np.ndarray) -> np.ndarray:
    a = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(a, z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = x, y, z, origin
    return m
