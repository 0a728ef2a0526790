"""pbrt-v4's lights as restir's emitters.

Every pbrt-v4 light divides its spectrum by the spectrum's luminance and multiplies by `scale`
(spectra.py gives the colour at luminance 1; an `rgb` keeps its own), then by the target power
when `power` (or a distant or infinite light's `illuminance`) is given, as pbrt-v4 defines it:
a point light's 4 pi, a spot's 2 pi (1 - (cos_start + cos_end) / 2), an area light's pi A (2 pi A
two-sided), an infinite light's pi. The film's imaging ratio (camera.py) multiplies all of them.
A spot's falloff is pbrt-v4's smoothstep between the cones at `coneangle - conedeltaangle` and
`coneangle`. An image infinite light's equal-area map is resampled to restir's
latitude-longitude map (image_infinite_light).
"""
import math
import os

import numpy as np

from ...image_io import read_image
from ..errors import SceneError, warn
from ..transforms import frame_along
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


def light_source(kind: str, ps: ParamSet, ctm: np.ndarray, ratio: float, base_dir: str = ".") -> dict:
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
        out = {"type": "spot", "to_world": frame_along(axis / np.linalg.norm(axis), pos), "intensity": i,
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
    elif ps.has("filename"):
        return image_infinite_light(ps, ctm, ratio, base_dir)
    else:
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


def image_infinite_light(ps: ParamSet, ctm: np.ndarray, ratio: float, base_dir: str) -> dict:
    """pbrt-v4's image infinite light: a square image in the equal-area octahedral mapping of the
    sphere (Clarberg's), looked up at the nearest texel, resampled here to restir's
    latitude-longitude map at 4n x 2n texels (each looking up pbrt-v4's texel in its direction; a
    warning says so), turned by the light's transform."""
    fname = ps.string("filename")
    path = fname if os.path.isabs(fname) else os.path.join(base_dir, fname)
    if not os.path.isfile(path):
        raise SceneError(f"infinite: environment map '{fname}' not found", ps.loc_of("filename"))
    for p in ("portal", "illuminance", "L"):
        if ps.has(p):
            raise SceneError(f"infinite: '{p}' with an image is not supported", ps.loc_of(p))
    try:
        img = read_image(path, linearize_srgb=True)
    except Exception as e:  # the image libraries raise many types
        raise SceneError(f"infinite: cannot read '{fname}': {e}", ps.loc_of("filename")) from None
    if img.shape[0] != img.shape[1] or not np.all(np.isfinite(img)):
        raise SceneError(f"infinite: '{fname}' must be a square image of finite values (pbrt-v4's equal-area map)",
                         ps.loc_of("filename"))
    scale = ps.float("scale", 1.0)
    if scale < 0:
        raise SceneError("a light's scale must be non-negative", ps.loc_of("scale"))
    latlong = equal_area_to_latlong(img)
    warn(f"infinite: the equal-area map '{fname}' ({img.shape[1]}x{img.shape[0]}) is resampled to a "
         f"latitude-longitude map ({latlong.shape[1]}x{latlong.shape[0]}, each texel pbrt-v4's nearest)", ps.loc)
    rot = np.eye(4)
    rot[:3, :3] = ctm[:3, :3] / np.linalg.norm(ctm[:3, :3], axis=0, keepdims=True)
    ps.warn_unused()
    return {"type": "envmap", "data": latlong, "scale": scale * ratio, "to_world": rot, "_loc": ps.loc}


def equal_area_sphere_to_square(d: np.ndarray) -> np.ndarray:
    """Clarberg's equal-area octahedral map of unit directions (N, 3) to [0, 1]^2, as pbrt-v4 uses
    for environment maps (+z at the centre, -z at the corners)."""
    x, y, z = np.abs(d[:, 0]), np.abs(d[:, 1]), np.abs(d[:, 2])
    r = np.sqrt(np.maximum(0.0, 1.0 - z))
    a, b = np.maximum(x, y), np.minimum(x, y)
    b = np.where(a == 0, 0.0, b / np.where(a == 0, 1.0, a))
    phi = np.arctan(b) * (2.0 / math.pi)
    phi = np.where(x < y, 1.0 - phi, phi)
    v = phi * r
    u = r - v
    neg = d[:, 2] < 0
    u, v = np.where(neg, 1.0 - v, u), np.where(neg, 1.0 - u, v)
    u, v = np.copysign(u, d[:, 0]), np.copysign(v, d[:, 1])
    return np.stack([0.5 * (u + 1.0), 0.5 * (v + 1.0)], axis=1)


def equal_area_to_latlong(img: np.ndarray) -> np.ndarray:
    """The latitude-longitude map (2n rows, 4n columns; restir's environment frame: row 0 at +y,
    u = phi / 2 pi with the direction (sin theta sin phi, cos theta, -sin theta cos phi)) of an
    n x n equal-area map, each texel the nearest of the equal-area map in its direction."""
    n = img.shape[0]
    h, w = 2 * n, 4 * n
    theta = math.pi * (np.arange(h) + 0.5) / h
    phi = 2 * math.pi * (np.arange(w) + 0.5) / w
    T, P = np.meshgrid(theta, phi, indexing="ij")
    d = np.stack([np.sin(T) * np.sin(P), np.cos(T), -np.sin(T) * np.cos(P)], -1).reshape(-1, 3)
    uv = equal_area_sphere_to_square(d)
    col = np.minimum((uv[:, 0] * n).astype(int), n - 1)
    row = np.minimum((uv[:, 1] * n).astype(int), n - 1)
    return np.ascontiguousarray(img[row, col].reshape(h, w, 3), np.float32)


class AreaLight:
    """An AreaLightSource "diffuse", read once; `emitter(area)` for each shape it lights (`power`
    needs the shape's world-space area)."""

    def __init__(self, kind: str, ps: ParamSet, ratio: float):
        if kind != "diffuse":
            raise SceneError(f"AreaLightSource '{kind}' is not supported (diffuse only)", ps.loc)
        self.twosided = ps.bool("twosided", False)
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
            # pbrt-v4 spreads the power over both sides of a two-sided emitter
            radiance = radiance * self.phi / (math.pi * area * (2 if self.twosided else 1))
        return {"type": "area", "radiance": radiance, "twosided": self.twosided, "_loc": self.loc}
