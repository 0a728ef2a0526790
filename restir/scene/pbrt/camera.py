"""pbrt-v4's camera, film, pixel filter, sampler and integrator as restir's sensor and integrator.

pbrt-v4's camera looks down +z with +x to the image's right; restir's (Mitsuba's) has +x to
the left, so the camera's world transform is the inverse of the CTM at `Camera`, mirrored in x.
`fov` spans the shorter image axis. The film's imaging ratio (shutter time x ISO / 100) scales
every emitter, which scales the image as pbrt-v4's sensor does.
"""
import numpy as np

from ... import limits
from ..errors import SceneError, warn
from .params import ParamSet

FILTERS = ("box", "triangle", "gaussian", "mitchell", "lanczos")


class Options:
    """What the directives before WorldBegin set."""

    def __init__(self):
        self.camera: tuple | None = None        # (ParamSet, camera-from-world CTM)
        self.film: ParamSet | None = None
        self.filter: tuple[str, ParamSet] | None = None
        self.sampler: tuple[str, ParamSet] | None = None
        self.integrator_spec: tuple[str, ParamSet] | None = None

    def imaging_ratio(self) -> float:
        """pbrt-v4's PixelSensor imaging ratio: the camera's shutter time x ISO / 100."""
        shutter = 1.0
        if self.camera is not None:
            ps = self.camera[0]
            shutter = ps.float("shutterclose", 1.0) - ps.float("shutteropen", 0.0)
            if shutter <= 0:
                raise SceneError("Camera: shutterclose must be after shutteropen", ps.loc)
        iso = 100.0
        if self.film is not None:
            iso = self.film.float("iso", 100.0)
            if iso <= 0:
                raise SceneError("Film: iso must be positive", self.film.loc_of("iso"))
        return shutter * iso / 100.0

    def sensor(self, path: str) -> dict:
        if self.camera is None:
            raise SceneError("the scene has no Camera", path)
        ps, ctm = self.camera
        try:
            world_from_camera = np.linalg.inv(ctm)
        except np.linalg.LinAlgError:
            raise SceneError("Camera: the transform before it is singular", ps.loc) from None
        to_world = world_from_camera @ np.diag([-1.0, 1.0, 1.0, 1.0])
        for p in ("screenwindow", "frameaspectratio"):
            if ps.has(p):
                raise SceneError(f"Camera: '{p}' is not supported", ps.loc_of(p))
        fov = ps.float("fov", 90.0)
        if not 0 < fov < 180:
            raise SceneError("Camera: fov must be in (0, 180) degrees", ps.loc_of("fov"))
        lens = ps.float("lensradius", 0.0)
        if lens < 0:
            raise SceneError("Camera: lensradius must be non-negative", ps.loc_of("lensradius"))
        focus = ps.float("focaldistance", 1e6)
        if focus <= 0:
            raise SceneError("Camera: focaldistance must be positive", ps.loc_of("focaldistance"))
        ps.ignore("shutteropen", "shutterclose")
        sensor = {"type": "thinlens" if lens > 0 else "perspective", "fov": fov, "fov_axis": "smaller",
                  "to_world": to_world, "_loc": ps.loc, "film": self._film(path), "sampler": self._sampler()}
        if lens > 0:
            sensor["aperture_radius"] = lens
            sensor["focus_distance"] = focus
        ps.warn_unused()
        return sensor

    def _film(self, path: str) -> dict:
        film = {"type": "hdrfilm", "width": 1280, "height": 720, "_loc": path}
        ps = self.film
        if ps is not None:
            film["_loc"] = ps.loc
            film["width"], film["height"] = ps.int("xresolution", 1280), ps.int("yresolution", 720)
            problem = limits.film_problem(film["width"], film["height"])
            if problem:
                raise SceneError(f"Film: {problem}", ps.loc)
            for p in ("cropwindow", "pixelbounds"):
                if ps.has(p):
                    raise SceneError(f"Film: '{p}' is not supported (the whole image is rendered)", ps.loc_of(p))
            sensor = ps.string("sensor", "cie1931")
            if sensor != "cie1931":
                warn(f"Film: sensor '{sensor}' is rendered with the CIE 1931 observer (linear sRGB): pbrt-v4's camera "
                     "response and its white balance at 6500 K are not applied, so colours differ", ps.loc_of("sensor"))
            wb = ps.float("whitebalance", 0.0)
            if wb != 0:
                warn(f"Film: whitebalance {wb:g} K is not applied (restir renders linear sRGB without adaptation)",
                     ps.loc_of("whitebalance"))
            mcv = ps.float("maxcomponentvalue", float("inf"))
            if np.isfinite(mcv):
                warn(f"Film: maxcomponentvalue {mcv:g} (pbrt-v4 clamps samples, which biases the image) is not applied",
                     ps.loc_of("maxcomponentvalue"))
            ps.ignore("filename", "savefp16", "diagonal", "iso")
            ps.warn_unused()
        film["rfilter"] = self._filter()
        return film

    def _filter(self) -> dict:
        if self.filter is None:  # pbrt-v4's default: gaussian, radius 1.5, sigma 0.5
            kind, ps = "gaussian", None
        else:
            kind, ps = self.filter
        if kind not in FILTERS:
            raise SceneError(f"PixelFilter '{kind}' is not supported (one of {', '.join(FILTERS)})", ps.loc)
        default = {"box": 0.5, "triangle": 2.0, "gaussian": 1.5, "mitchell": 2.0, "lanczos": 4.0}[kind]
        rx = ps.float("xradius", default) if ps else default
        ry = ps.float("yradius", default) if ps else default
        if rx != ry:
            raise SceneError("PixelFilter: different xradius and yradius are not supported", ps.loc)
        if rx <= 0:
            raise SceneError("PixelFilter: the radius must be positive", ps.loc)
        loc = ps.loc if ps else None
        if kind == "box":
            out = {"type": "box", "radius": rx}
        elif kind == "triangle":
            out = {"type": "tent", "radius": rx}
        else:
            sigma = ps.float("sigma", 0.5) if (ps and kind == "gaussian") else 0.5
            if ps:
                ps.ignore("B", "C", "tau")
            what = {"gaussian": f"gaussian (radius {rx:g}, sigma {sigma:g}, shifted to zero at the radius)",
                    "mitchell": f"mitchell (radius {rx:g})", "lanczos": f"lanczos (radius {rx:g})"}[kind]
            if ps is not None:
                warn(f"PixelFilter: pbrt-v4's {what} is rendered as restir's nearest, a gaussian of standard deviation "
                     f"{sigma:g} (radius {4 * sigma:g}, not shifted)", loc)
            out = {"type": "gaussian", "stddev": sigma}
        if ps:
            ps.warn_unused()
        return out

    def _sampler(self) -> dict:
        spp = 16
        if self.sampler is not None:
            kind, ps = self.sampler
            spp = ps.int("pixelsamples", 16)
            ps.ignore("seed", "dimensions", "jitter", "randomization", "xsamples", "ysamples")
            ps.warn_unused()
        return {"type": "independent", "sample_count": spp}

    def integrator(self) -> dict:
        """pbrt-v4's maxdepth counts bounces (5 by default); restir's max_depth counts path
        segments as Mitsuba's does: max_depth = maxdepth + 1."""
        if self.integrator_spec is None:
            return {"type": "path", "max_depth": 6}
        kind, ps = self.integrator_spec
        depth = ps.int("maxdepth", 5)
        if depth < 0:
            raise SceneError("Integrator: maxdepth must be non-negative", ps.loc_of("maxdepth"))
        if ps.bool("regularize", False):
            raise SceneError("Integrator: 'regularize' (a biased roughening of paths) is not supported",
                             ps.loc_of("regularize"))
        if kind not in ("path", "volpath"):
            warn(f"Integrator '{kind}' is rendered with restir's own methods (maxdepth {depth} is kept)", ps.loc)
        ps.ignore("lightsampler", "samplelights", "samplebsdf", "visualizestrategies", "visualizeweights",
                  "bootstraplightsamples", "chains", "mutationsperpixel", "largestepprobability", "sigma",
                  "iterations", "photonsperiteration", "radius", "seed", "cossample", "maxdistance")
        ps.warn_unused()
        return {"type": "path", "max_depth": depth + 1}
