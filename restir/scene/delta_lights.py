"""Delta lights on the host: the description every loader maps its point, spot and directional
lights onto (device/delta_lights.py renders them), and their power, which light selection
divides among all lights (scene/upload.py).

A spot's cone is its inner and outer half-angles and a falloff kind that says how the intensity
goes from full (inside the inner cone) to none (outside the outer one), as each format defines it:
Mitsuba 3's `spot` (beam_width, cutoff_angle; linear in the angle), pbrt-v4's `spot`
(coneangle - conedeltaangle, coneangle; smoothstep in the cosine), glTF's spot (innerConeAngle,
outerConeAngle; a squared ramp in the cosine).
"""
import math
from dataclasses import dataclass, field

import numpy as np

LUMINANCE = np.array([0.2126, 0.7152, 0.0722])
FALLOFFS = ("linear_angle", "smoothstep", "squared_ramp")


@dataclass
class DeltaLightDesc:
    kind: str                      # "point", "spot" or "directional"
    intensity: np.ndarray          # RGB: W/sr (point, spot) or irradiance W/m^2 (directional)
    position: np.ndarray = field(default_factory=lambda: np.zeros(3))
    axis: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, 1.0]))  # spot: shines along; directional: travels along
    falloff: str = "linear_angle"  # spot: "linear_angle", "smoothstep" or "squared_ramp"
    inner: float = 0.0             # spot: half-angles in radians, inner <= outer
    outer: float = 0.0

    def falloff_at(self, cos_theta: np.ndarray) -> np.ndarray:
        """The spot's falloff (1 for a point light), for its power: the formats' definitions,
        as device/delta_lights.spot_falloff evaluates them."""
        c = np.asarray(cos_theta, np.float64)
        if self.kind != "spot":
            return np.ones_like(c)
        ci, co = math.cos(self.inner), math.cos(self.outer)
        if self.falloff == "squared_ramp":
            return np.clip((c - co) / max(0.001, ci - co), 0.0, 1.0) ** 2
        if self.falloff == "linear_angle":
            ramp = (self.outer - np.arccos(np.clip(c, -1.0, 1.0))) / max(self.outer - self.inner, 1e-30)
        else:
            t = np.clip((c - co) / max(ci - co, 1e-30), 0.0, 1.0)
            ramp = t * t * (3.0 - 2.0 * t)
        return np.where(c <= co, 0.0, np.where(c >= ci, 1.0, ramp))

    def power(self, scene_radius: float) -> float:
        """Emitted power (luminance) divided by pi, the constant Scene.light_power leaves out of
        the triangles' (pi L A for a one-sided diffuse emitter): a point's 4 pi I, a spot's I times
        its falloff integrated over the sphere, a directional light's E pi r^2 over the disc of the
        scene's bounding sphere (as pbrt-v4 defines a distant light's power)."""
        lum = float(np.maximum(np.asarray(self.intensity, np.float64) @ LUMINANCE, 0.0))
        if self.kind == "directional":
            return lum * scene_radius ** 2
        if self.kind == "point":
            return 4.0 * lum
        # 2 pi times the falloff's integral over cos theta (midpoint rule, fine for a selection
        # probability), over pi
        n = 4096
        c = -1.0 + (np.arange(n) + 0.5) * (2.0 / n)
        return 2.0 * lum * float(self.falloff_at(c).sum() * (2.0 / n))
