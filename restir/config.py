"""Render configuration: the common settings and each method's documented, typed settings.

Method settings (`--set key=value`) are validated against the method's settings dataclass
(restir/settings.py); an unknown key is an error, never silently ignored.
"""
from dataclasses import dataclass, field


class ConfigError(ValueError):
    pass


AOVS = ("albedo", "normal")  # the extra outputs a render can write (restir/aov.py computes them)


def check_aovs(names, given: str | None = None) -> tuple:
    """The AOV names, checked: an unknown name (or none, from --aov) is an error naming them."""
    names = tuple(names)
    bad = [n for n in names if n not in AOVS]
    if bad or (given is not None and not names):
        where = f"--aov {given}: " if given is not None else ""
        raise ConfigError(f"{where}unknown AOV {', '.join(bad) or '(none given)'} (available: {', '.join(AOVS)})")
    return names


def parse_aovs(text: str) -> tuple:
    """--aov albedo,normal -> ("albedo", "normal")."""
    return check_aovs((s.strip() for s in text.split(",") if s.strip()), given=text)


@dataclass
class RenderConfig:
    method: str = "pt"
    spp: int | None = None          # samples per pixel per frame (None: the scene's sample_count)
    frames: int = 1                 # frames rendered; the output is their average
    width: int | None = None        # None: the scene's film size
    height: int | None = None
    max_depth: int | None = None    # Mitsuba's meaning; None: the scene's integrator max_depth
    seed: int = 0
    device: str = "cpu"
    settings: dict = field(default_factory=dict)   # method settings {key: value} (`restir info` lists them)
    slices: int | None = None       # CPU launch slices (None: one per core)
    debug_reverse_launch: bool = False  # run CPU slices sequentially, last first (race test R2)
    tracer: str = "auto"            # "auto" (Embree on the CPU if available), "embree", "warp"
    keep_frames: bool = False       # keep every frame's image (RenderResult.frame_images), for statistics
    camera_motion: str = "none"     # "none", "orbit" (speed: degrees/frame), "dolly" (speed: scene sizes/frame)
    camera_speed: float = 1.0
    aovs: tuple = ()                # extra outputs: "albedo", "normal" (RenderResult.aovs; restir/aov.py)
    jitter: bool = True             # False: every primary ray through its pixel centre (device/camera.py)

    def validate(self) -> None:
        from . import limits

        problems = [limits.side_problem(k, getattr(self, k)) for k in ("width", "height")
                    if getattr(self, k) is not None]
        problems += [limits.spp_problem(self.spp) if self.spp is not None else None,
                     limits.frames_problem(self.frames),
                     limits.depth_problem(self.max_depth) if self.max_depth is not None else None,
                     limits.finite_problem("camera_speed", self.camera_speed)]
        problem = next((p for p in problems if p), None)
        if problem:
            raise ConfigError(problem)
        if self.camera_motion not in ("none", "orbit", "dolly"):
            raise ConfigError("camera_motion must be none, orbit or dolly")
        if self.tracer not in ("auto", "embree", "warp"):
            raise ConfigError("tracer must be auto, embree or warp")
        if not 0 <= self.seed < 2**32:
            raise ConfigError("seed must be in [0, 2^32)")
        check_aovs(self.aovs)


def parse_value(text: str, like):
    """Parse a --set value with the type of the setting's default."""
    if isinstance(like, bool):
        t = text.strip().lower()
        if t in ("1", "true", "yes", "on"):
            return True
        if t in ("0", "false", "no", "off"):
            return False
        raise ConfigError(f"'{text}' is not a boolean")
    try:
        if isinstance(like, int):
            return int(text)
        if isinstance(like, float):
            return float(text)
    except ValueError:
        name = type(like).__name__
        raise ConfigError(f"'{text}' is not {'an' if name[0] in 'aeiou' else 'a'} {name}") from None
    return text
