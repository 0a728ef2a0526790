"""The largest inputs restir accepts, each refused with a one-line error before any work is done
(docs/reference/limits.md): a film, sample count or path depth beyond them would exhaust the device's
memory, overflow the kernels' 32-bit indices or run for days, and a number that is not finite
has no meaning anywhere. The scene loader (with the file and line) and the API's configs (the
command line's arguments) ask the same questions here."""
import math

MAX_FILM_SIDE = 16384           # pixels on either side of the film
MAX_FILM_PIXELS = 8192 * 8192   # 67 M pixels: Suffix ReSTIR's buffers (about 400 B a pixel) take 27 GB there
MAX_SPP = 65536                 # samples per pixel per frame
MAX_FRAMES = 1 << 24
MAX_DEPTH = 1023                # the longest path a sample's random numbers are laid out for (device/streams.py)
MAX_SECONDS = 7 * 24 * 3600     # a time budget (restir compare --equal-time)
MAX_RUNS = 1 << 16              # independent runs (validate --runs, sweep --seeds, compare --correlation-runs)
MAX_SCENE_FILE_BYTES = 256 << 20  # a scene's XML file (its meshes and images are files of their own)
MAX_XML_DEPTH = 64              # elements nested in a scene file (Mitsuba's scenes nest 4 or 5 deep)


def film_problem(width: int, height: int) -> str | None:
    """Why a film of width x height is refused, or None."""
    if width < 1 or height < 1:
        return f"the film must be at least 1x1 pixel (got {width}x{height})"
    if width > MAX_FILM_SIDE or height > MAX_FILM_SIDE:
        return f"the film is {width}x{height}: at most {MAX_FILM_SIDE} pixels a side"
    if width * height > MAX_FILM_PIXELS:
        return f"the film is {width}x{height}: at most {MAX_FILM_PIXELS} pixels ({MAX_FILM_PIXELS >> 20} M)"
    return None


def side_problem(name: str, pixels: int) -> str | None:
    """Why a film side (`width`, `height`) of `pixels` is refused, or None."""
    if not 1 <= pixels <= MAX_FILM_SIDE:
        return f"{name} must be in [1, {MAX_FILM_SIDE}] pixels (got {pixels})"
    return None


def spp_problem(spp: int, name: str = "spp") -> str | None:
    if not 1 <= spp <= MAX_SPP:
        return f"{name} must be in [1, {MAX_SPP}] per frame (got {spp}); more frames give more samples"
    return None


def frames_problem(frames: int) -> str | None:
    if not 1 <= frames <= MAX_FRAMES:
        return f"frames must be in [1, {MAX_FRAMES}] (got {frames})"
    return None


def runs_problem(option: str, runs: int, least: int) -> str | None:
    if not least <= runs <= MAX_RUNS:
        return f"{option} must be in [{least}, {MAX_RUNS}] (got {runs})"
    return None


def depth_problem(max_depth: int) -> str | None:
    if max_depth != -1 and not 1 <= max_depth <= MAX_DEPTH:
        return f"max_depth must be -1 (unbounded, up to {MAX_DEPTH} segments) or in [1, {MAX_DEPTH}] (got {max_depth})"
    return None


def finite_problem(name: str, value: float) -> str | None:
    if not math.isfinite(value):
        return f"{name} must be a finite number (got {value})"
    return None
