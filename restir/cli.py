"""Command line: `restir render SCENE ...` (the contract in DESIGN.md "Command line").

Parses arguments into a RenderConfig and calls the API; user errors print one line
(`file:line: error: ...`, or `restir render: error: ...` for a bad argument) and exit with
status 2, never a traceback. Output paths are checked before any work is done.
"""
import argparse
import json
import math
import os
import sys
import tempfile
import textwrap
import warnings

from .config import ConfigError, RenderConfig
from .fanout import default_workers
from .image_io import IMAGE_FORMATS, LDR_FORMATS
from .scene.builtin import BUILTIN_DESCRIPTIONS, BUILTINS
from .scene.errors import SceneError, SceneWarning

# restir.validation.runs.DEFAULT_MAX_MDB as --max-mdb writes it (not imported: that pulls in scipy)
DEFAULT_MAX_MDB = "5%"


class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors (no usage block), status 2."""

    def error(self, message):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


class _Formatter(argparse.ArgumentDefaultsHelpFormatter, argparse.RawDescriptionHelpFormatter):
    """Shows '(default: ...)' after each option's help, except where there is no default to show
    (None, off flags, empty lists) or the help already says it."""

    def _get_help_string(self, action):
        d = action.default
        if d is None or d is False or d == [] or "default" in (action.help or ""):
            return action.help
        return super()._get_help_string(action)


def _key_value(text: str) -> tuple[str, str]:
    if "=" not in text:
        raise argparse.ArgumentTypeError(f"expected NAME=VALUE, got '{text}'")
    k, v = text.split("=", 1)
    return k.strip(), v.strip()


def _fraction(text: str) -> float:
    """A bound on a relative bias: a fraction (0.05) or a percentage (5%)."""
    t = text.strip()
    try:
        v = float(t[:-1]) / 100 if t.endswith("%") else float(t)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a fraction such as 0.05 or a percentage such as 5%, got '{text}'") from None
    if not (v > 0 and math.isfinite(v)):
        raise argparse.ArgumentTypeError(f"must be above 0, got '{text}'")
    if not t.endswith("%") and v > 1:
        raise argparse.ArgumentTypeError(f"'{text}' as a fraction is over 100%; a percentage needs %, e.g. {t}%")
    return v


def _builtins_epilog() -> str:
    lines = ["builtin scenes (SCENE = builtin:NAME):"]
    for name, text in BUILTIN_DESCRIPTIONS.items():
        lines += textwrap.wrap(text, 96, initial_indent=f"  {name:<20}", subsequent_indent=" " * 22)
    return "\n".join(lines)


def build_parser() -> argparse.ArgumentParser:
    from . import __version__

    ap = _Parser(prog="restir", description="Research renderer for resampled path tracing.")
    ap.add_argument("--version", action="version", version=f"restir {__version__}")
    sub = ap.add_subparsers(dest="command", required=True)
    r = sub.add_parser("render", help="render a scene", formatter_class=_Formatter, epilog=_builtins_epilog())
    r.add_argument("scene", help="Mitsuba 3 XML file or builtin:NAME (listed below)")
    r.add_argument("--method", default="pt", help="pt (path tracer), restir-di (direct light: emission plus one "
                   "bounce; docs/restir_di.md), restir-pt (path reuse; docs/restir_pt.md) or suffix-restir "
                   "(conditional suffix reuse with a final gather; docs/suffix_restir.md); settings with --set, "
                   "listed by `restir info`")
    r.add_argument("--spp", type=int, help="samples per pixel per frame (default: the scene's)")
    r.add_argument("--frames", type=int, default=1, help="frames to render and average")
    r.add_argument("--width", type=int, help="image width in pixels (default: the scene's)")
    r.add_argument("--height", type=int, help="image height in pixels (default: the scene's)")
    r.add_argument("--max-depth", type=int, help="Mitsuba's max_depth, -1: unbounded (default: the scene's; "
                   "restir-di computes 2 only; restir-pt and suffix-restir up to 64)")
    r.add_argument("--seed", type=int, default=0, help="random seed")
    r.add_argument("--device", default="cpu", help="cpu or cuda (or cuda:N)")
    r.add_argument("--tracer", default="auto", choices=["auto", "embree", "warp"],
                   help="CPU ray tracer (auto: Embree if available; CUDA always uses Warp's BVH)")
    r.add_argument("--camera-motion", default="none", choices=["none", "orbit", "dolly"],
                   help="scripted camera motion over the frames (the scene stays static)")
    r.add_argument("--camera-speed", type=float, default=1.0,
                   help="orbit: degrees per frame; dolly: scene diagonals per frame")
    r.add_argument("-D", dest="defines", action="append", type=_key_value, default=[], metavar="NAME=VALUE",
                   help="override a scene <default> (as Mitsuba's -D)")
    r.add_argument("--set", dest="settings", action="append", type=_key_value, default=[], metavar="KEY=VALUE",
                   help="method setting, e.g. strategy=nee")
    r.add_argument("-o", "--output", metavar="FILE",
                   help="the image, format by extension: .exr (linear float), .png or .jpg (tonemapped sRGB, "
                        "with --exposure), .npy (float32 linear, H x W x 3) (default: <scene name>.exr in the "
                        "current folder)")
    r.add_argument("--png", metavar="FILE", help="also write a tonemapped sRGB PNG (or .jpg)")
    r.add_argument("--exposure", type=float, default=0.0, help="exposure in stops of the tonemapped images")
    r.add_argument("--stats", metavar="FILE", help="write the stats JSON here")
    r.add_argument("--write-frames", metavar="DIR",
                   help="also write every frame's image as DIR/frame_0000.exr, frame_0001.exr, ...")
    r.add_argument("--quiet", action="store_true", help="no progress bar, timing table or notes")
    r.add_argument("--aov", metavar="NAMES", help="also write these layers into the EXR: albedo, normal (comma-"
                   "separated; channels albedo.R/G/B, normal.X/Y/Z, as Mitsuba's aov integrator), for denoisers")
    r.add_argument("--tev", nargs="?", const="127.0.0.1:14158", metavar="HOST:PORT",
                   help="also send the image (and AOVs) to a running tev viewer (needs restir[tev]; default "
                        "127.0.0.1:14158)")

    sub.add_parser("info", help="list the methods with their settings (defaults, meanings) and the builtin scenes")
    v = sub.add_parser("validate", formatter_class=_Formatter, epilog=_builtins_epilog(),
                       help="test a method for bias against the path tracer (independent runs, z-tests)")
    v.add_argument("scene", nargs="?", help="Mitsuba 3 XML file or builtin:NAME (listed below); not needed when "
                   "--images are tested against --reference images")
    v.add_argument("--method", default="restir-di", help="the method tested")
    v.add_argument("--images", metavar="GLOB", help="test these images instead of rendering: K >= 2 independent runs "
                   "of any renderer (quote the pattern, e.g. 'runs/*.exr'), against --reference, or against the "
                   "path tracer rendered here on SCENE (--ref-runs runs of --frames x --ref-spp at the images' size)")
    v.add_argument("--reference", metavar="GLOB", help="with --images: K' >= 2 independent reference runs, or one "
                   "converged image (taken as exact unless --reference-variance is given)")
    v.add_argument("--reference-variance", metavar="FILE", help="with one --reference image: the per-pixel variance "
                   "of its mean, an image of the same size")
    v.add_argument("--runs", type=int, default=32, help="independent runs K (fresh seed and history each)")
    v.add_argument("--frames", type=int, default=8, help="frames T per run; a run's statistic is its average")
    v.add_argument("--spp", type=int, default=1, help="samples per pixel per frame of the tested method")
    v.add_argument("--width", type=int, default=32, help="image width in pixels")
    v.add_argument("--height", type=int, default=32, help="image height in pixels")
    v.add_argument("--max-depth", type=int, help="depth of both sides (default: the method's, restir-di: 2, "
                   "or the scene's)")
    v.add_argument("--set", dest="settings", action="append", type=_key_value, default=[], metavar="KEY=VALUE",
                   help="setting of the tested method")
    v.add_argument("-D", dest="defines", action="append", type=_key_value, default=[], metavar="NAME=VALUE",
                   help="override a scene <default> (as Mitsuba's -D)")
    v.add_argument("--ref-spp", type=int, default=4, help="path-tracer spp per frame of the reference runs")
    v.add_argument("--ref-runs", type=int, help="reference runs (default: --runs)")
    v.add_argument("--max-mdb", type=_fraction, default=DEFAULT_MAX_MDB, metavar="BOUND",
                   help="largest minimum detectable bias (relative, 80%% power) a pass may have, as a fraction "
                        "(0.05) or a percentage (5%%); above it the verdict is inconclusive (exit 3)")
    v.add_argument("--camera-motion", default="none", choices=["none", "orbit", "dolly"],
                   help="scripted camera motion over the frames")
    v.add_argument("--camera-speed", type=float, default=1.0, help="orbit: degrees per frame; dolly: scene "
                   "diagonals per frame")
    v.add_argument("--device", default="cpu", help="cpu or cuda (or cuda:N)")
    v.add_argument("--zmap", metavar="FILE", help="write the per-pixel z map here (.png, .exr, .npy)")
    _fanout_options(v, default_workers=None, what="the independent runs")
    c = sub.add_parser("compare", formatter_class=_Formatter, epilog=_builtins_epilog(),
                       help="compare methods at equal time or equal samples against a reference (metrics, report)")
    c.add_argument("scene", help="Mitsuba 3 XML file or builtin:NAME (listed below)")
    c.add_argument("--method", dest="methods", action="append", default=[], metavar="NAME[:key=value,...]",
                   help="a method to compare, with its settings (spp=N: samples per pixel per frame); repeat "
                        "for each method, e.g. --method pt --method 'restir-di:spatial.neighbors=8'")
    c.add_argument("--reference", metavar="FILE", help="reference image (.exr, .npy, .png) of the compared size, or "
                   "'mitsuba': Mitsuba 3 at --reference-spp on the same XML (restir[reference]) (default: the path "
                   "tracer at --reference-spp; both cached under ~/.cache/restir or $RESTIR_CACHE)")
    c.add_argument("--reference-spp", type=int, default=1024, help="spp of the path-traced reference")
    budget = c.add_mutually_exclusive_group()
    budget.add_argument("--equal-time", type=float, metavar="SECONDS",
                        help="every method renders frames for this wall time (compilation excluded)")
    budget.add_argument("--equal-spp", type=int, metavar="N", help="every method renders N samples per pixel")
    c.add_argument("--frames", type=int, default=16, help="frames per method when no budget is given")
    c.add_argument("--warmup", type=int, default=4, help="frames before the per-frame error is measured")
    c.add_argument("--seed", type=int, default=0, help="random seed")
    c.add_argument("--width", type=int, help="image width (default: the scene's)")
    c.add_argument("--height", type=int, help="image height (default: the scene's)")
    c.add_argument("--max-depth", type=int, help="max_depth of every method and the reference (default: the "
                   "scene's; 2 when restir-di is compared)")
    c.add_argument("-D", dest="defines", action="append", type=_key_value, default=[], metavar="NAME=VALUE",
                   help="override a scene <default> (as Mitsuba's -D)")
    c.add_argument("--device", default="cpu", help="cpu or cuda (or cuda:N)")
    c.add_argument("--report", metavar="DIR", help="write the HTML report (opens offline) into this folder")
    c.add_argument("--json", metavar="FILE", help="write the metrics, timings and stats as JSON")
    c.add_argument("--quiet", action="store_true", help="no progress display")
    _fanout_options(c, default_workers=None, what="the correlation runs, and the methods at equal samples or "
                    "frames (equal time renders them one after another)")
    c.add_argument("--denoise", action="store_true", help="also denoise the frames after the warm-up (all, or an "
                   "evenly spaced subset of 9-16) and the last frame with Open Image Denoise (albedo and normal "
                   "guides; needs restir[denoise]): per-frame denoised relMSE and FLIP, the images in the report")
    c.add_argument("--correlation-runs", type=int, default=8, metavar="K",
                   help="independent runs (warmup + 1 frames each) per method for the radial correlation; 0: none")
    c.add_argument("--no-frame-time-match", dest="match_frame_time", action="store_false",
                   help="at equal time, do not also render the path tracer at each other method's frame time "
                        "(the per-frame baseline of the headline)")
    c.add_argument("--tev", nargs="?", const="127.0.0.1:14158", metavar="HOST:PORT",
                   help="also send the reference and every method's image to a running tev (needs restir[tev])")

    s = sub.add_parser("sweep", formatter_class=_Formatter, epilog=_builtins_epilog(),
                       help="one method over a grid of settings and seeds, fanned out locally or on Ray")
    s.add_argument("scene", help="Mitsuba 3 XML file or builtin:NAME (listed below)")
    s.add_argument("--method", required=True, help="the method swept (restir info lists its settings)")
    s.add_argument("--grid", action="append", default=[], metavar="KEY=V1,V2,...",
                   help="a setting and its values (spp: samples per pixel per frame); repeat for more axes: "
                        "every combination is rendered")
    s.add_argument("--seeds", type=int, default=1, help="seeds per grid point (0 .. N-1)")
    s.add_argument("--frames", type=int, default=16, help="frames per render")
    s.add_argument("--spp", type=int, default=1, help="samples per pixel per frame (unless on the grid)")
    s.add_argument("--warmup", type=int, default=4, help="frames before the per-frame error is measured")
    s.add_argument("--reference", metavar="FILE", help="reference image (default: the path tracer at "
                   "--reference-spp, cached)")
    s.add_argument("--reference-spp", type=int, default=1024, help="spp of the path-traced reference")
    s.add_argument("--width", type=int, help="image width (default: the scene's)")
    s.add_argument("--height", type=int, help="image height (default: the scene's)")
    s.add_argument("--max-depth", type=int, help="max_depth (default: the scene's)")
    s.add_argument("-D", dest="defines", action="append", type=_key_value, default=[], metavar="NAME=VALUE",
                   help="override a scene <default> (as Mitsuba's -D)")
    s.add_argument("--device", default="cpu", help="cpu or cuda (or cuda:N)")
    s.add_argument("--out", default="out/sweep", metavar="DIR", help="writes DIR/sweep.json, DIR/sweep.csv and "
                   "the report DIR/report/index.html")
    s.add_argument("--quiet", action="store_true", help="no progress display")
    _fanout_options(s, default_workers=None, what="the renders")
    return ap


def _fanout_options(p, default_workers, what):
    p.add_argument("--workers", type=int, default=default_workers,
                   help=f"local processes rendering {what} (default: "
                        f"{'one per core' if default_workers is None else default_workers})")
    p.add_argument("--ray", metavar="ADDRESS", help=f"render {what} on a Ray cluster: auto (the running one), an "
                   "address (ray://host:10001), or local (a private one on this machine); needs restir[ray]")


# ------------------------------------------------------------------ output paths, checked first
def _writable_folder(folder: str, what: str) -> None:
    """Create `folder` if missing (as the writers would) and make sure a file can be made there."""
    existing = folder
    while not os.path.exists(existing) and os.path.dirname(existing) != existing:
        existing = os.path.dirname(existing)
    if not os.path.isdir(existing):
        raise ConfigError(f"{what}: '{existing}' is not a folder")
    try:
        os.makedirs(folder, exist_ok=True)
    except OSError as e:
        missing = folder
        while not os.path.exists(os.path.dirname(missing)):
            missing = os.path.dirname(missing)
        raise ConfigError(f"{what}: cannot create folder '{missing}': {e.strerror}") from None
    try:
        fd, probe = tempfile.mkstemp(dir=folder, prefix=".restir-write-test-")
        os.close(fd)
        os.remove(probe)
    except OSError as e:
        raise ConfigError(f"{what}: cannot write in folder '{folder}': {e.strerror}") from None


def check_output(path: str, option: str, formats=None) -> None:
    """Refuse now, before the render, an output file that could not be written after it: a
    folder, an extension not in `formats` (when given), a folder that cannot be created or
    written, a file that cannot be overwritten."""
    what = f"{option} {path}"
    if path.endswith(("/", os.sep)) or os.path.isdir(path):
        raise ConfigError(f"{what}: is a folder; give a file name")
    if formats is not None:
        ext = os.path.splitext(path)[1].lower()
        if ext not in formats:
            why = f"unsupported extension '{ext}'" if ext else "no extension to choose the format by"
            raise ConfigError(f"{what}: {why} (use {', '.join(formats)})")
    _writable_folder(os.path.dirname(os.path.abspath(path)), what)
    if os.path.exists(path) and not os.access(path, os.W_OK):
        raise ConfigError(f"{what}: the file exists and cannot be overwritten")


def check_output_folder(path: str, option: str) -> None:
    what = f"{option} {path}"
    if os.path.exists(path) and not os.path.isdir(path):
        raise ConfigError(f"{what}: not a folder")
    _writable_folder(os.path.abspath(path), what)


def default_output(scene_spec: str) -> str:
    """<scene name>.exr in the current folder, as Mitsuba names it (builtin name or XML file stem)."""
    if scene_spec.startswith("builtin:"):
        name = scene_spec.split(":", 1)[1]
    else:
        name = os.path.splitext(os.path.basename(scene_spec))[0]
    return (name or "render") + ".exr"


def _write(path: str, write, *args) -> None:
    try:
        write(path, *args)
    except OSError as e:  # after the checks: a full disk, a folder removed meanwhile, ...
        raise ConfigError(f"cannot write {path}: {e.strerror or e}") from None


def _write_json(path: str, data: dict) -> None:
    with open(path, "w") as f:
        json.dump(data, f, indent=2, default=str)


def _load_scene(spec: str, defines, report):
    """api.load_scene with its SceneWarnings passed to `report` (one line each)."""
    from . import api

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", SceneWarning)
        scene = api.load_scene(spec, dict(defines) or None)
    for w in caught:
        if issubclass(w.category, SceneWarning):
            report(str(w.message))
        else:
            warnings.showwarning(w.message, w.category, w.filename, w.lineno)
    return scene


# ------------------------------------------------------------------ commands
def _render(args) -> int:
    from rich.console import Console
    from rich.markup import escape
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TimeElapsedColumn, TimeRemainingColumn
    from rich.table import Table

    from . import api
    from .image_io import write_exr, write_image, write_png

    console = Console(stderr=True, quiet=args.quiet)
    from .config import parse_aovs

    aovs = parse_aovs(args.aov) if args.aov else ()
    config = RenderConfig(method=args.method, spp=args.spp, frames=args.frames, width=args.width,
                          height=args.height, max_depth=args.max_depth, seed=args.seed, device=args.device, tracer=args.tracer,
                          camera_motion=args.camera_motion, camera_speed=args.camera_speed,
                          settings=dict(args.settings), keep_frames=bool(args.write_frames), aovs=aovs)
    config.validate()
    output = args.output or default_output(args.scene)
    check_output(output, "-o" if args.output else "output", tuple(IMAGE_FORMATS))
    if aovs and not output.lower().endswith(".exr"):
        raise ConfigError(f"--aov writes layers of an EXR; the output {output} is not .exr")
    tev = None
    if args.tev:
        from .viewer import connect_tev

        tev = connect_tev(args.tev)  # before the render: a missing package or viewer is said now
    if args.png:
        check_output(args.png, "--png", LDR_FORMATS)
    if args.stats:
        check_output(args.stats, "--stats")
    if args.write_frames:
        check_output_folder(args.write_frames, "--write-frames")

    scene = _load_scene(args.scene, args.defines,
                        lambda m: console.print(f"[yellow]warning:[/] {escape(m)}", highlight=False, soft_wrap=True))
    with Progress("[progress.description]{task.description}", BarColumn(), MofNCompleteColumn(),
                  TimeElapsedColumn(), TimeRemainingColumn(), console=console, transient=True) as bar:
        task = bar.add_task(f"{config.method} frames", total=config.frames)
        try:
            result = api.render(scene, config, progress=lambda done, total: bar.update(task, completed=done),
                                on_compile=lambda: console.print("compiling kernels (once per configuration; "
                                                                 "later runs load them from Warp's cache)..."))
        except api.RenderInterrupted as e:
            result = e.result
    if result is None:
        print("interrupted before the first frame finished: nothing written", file=sys.stderr)
        return 130
    interrupted = result.stats.get("interrupted", False)
    if interrupted:
        print(f"interrupted after {result.frames} finished frame(s) of {config.frames}: writing their average",
              file=sys.stderr)
    if result.aovs:
        from .image_io import write_exr as _write_exr

        _write(output, _write_exr, result.image, result.aovs)
    else:
        _write(output, write_image, result.image, args.exposure)
    written = [output]
    if tev is not None:
        from .viewer import send_to_tev

        send_to_tev(tev, f"{result.stats['method']} {result.stats['scene']}", result.image, result.aovs)
        tev.__exit__(None, None, None)
    if args.png:
        _write(args.png, write_png, result.image, args.exposure)
        written.append(args.png)
    if args.write_frames:
        for i, frame in enumerate(result.frame_images):
            _write(os.path.join(args.write_frames, f"frame_{i:04d}.exr"), write_exr, frame)
        written.append(os.path.join(args.write_frames, f"frame_0000.exr ... frame_{len(result.frame_images) - 1:04d}.exr"))
    if args.stats:
        _write(args.stats, _write_json, result.stats)
        written.append(args.stats)
    st = result.stats
    for note in st.get("notes", []):
        console.print(f"note: {escape(note)}", highlight=False, soft_wrap=True)
    table = Table(title=f"{st['method']} on {st['scene']} ({st['width']}x{st['height']}, "
                        f"{st['spp_per_frame']} spp x {st['frames']} frames, max_depth {st['max_depth']}, "
                        f"{st['device']}, {st['tracer']})")
    table.add_column("stage")
    table.add_column("ms per frame", justify="right")
    for name, s in st["stages"].items():
        table.add_row(name, f"{s['total_ms'] / st['frames']:.1f}")
    table.add_row("total", f"{st['ms_per_frame']:.1f}")
    console.print(table)
    console.print(f"{st['rays_per_second'] / 1e6:.2f} Mrays/s, "
                  f"{st['bytes_per_pixel']['total']:.0f} bytes/pixel in render buffers")
    for path in written:
        console.print(f"wrote {escape(path)}", highlight=False, soft_wrap=True)
    return 130 if interrupted else 0


def _glob_images(pattern: str, option: str) -> list:
    import glob

    from .image_io import read_image

    paths = sorted(glob.glob(os.path.expanduser(pattern)))
    if not paths:
        raise ConfigError(f"{option} {pattern}: no file matches")
    images = []
    for p in paths:
        try:
            images.append(read_image(p))
        except Exception as e:  # unreadable or not an image: name the file
            raise ConfigError(f"{option}: cannot read {p}: {e}") from None
    return images


def _print_validation(result, max_mdb) -> None:
    for channel, rep in zip("RGB", result.report.reports):
        print(f"{channel}: {rep}")
    print(f"minimum detectable bias (image level, 80% power): {100 * result.report.mdb:.2f}% "
          f"(a pass needs at most {100 * max_mdb:.3g}%, --max-mdb)")


def _validate_images(args) -> int:
    from .image_io import write_image
    from .validation import validate_images

    if args.zmap:
        check_output(args.zmap, "--zmap", tuple(IMAGE_FORMATS))
    if args.reference_variance and not args.reference:
        raise ConfigError("--reference-variance needs --reference")
    images = _glob_images(args.images, "--images")
    if len(images) < 2:
        raise ConfigError(f"--images {args.images}: {len(images)} file; at least 2 independent runs are needed")
    if args.reference:
        refs = _glob_images(args.reference, "--reference")
        if len(refs) >= 2:
            if args.reference_variance:
                raise ConfigError("--reference-variance goes with one converged --reference image, not several runs")
            what = f"{len(refs)} reference runs"
            result = validate_images(images, reference_images=refs, max_mdb=args.max_mdb)
        else:
            var = 0.0
            if args.reference_variance:
                var = _glob_images(args.reference_variance, "--reference-variance")[0][..., :3]
            what = "one converged reference" + (" with its variance" if args.reference_variance else " (taken as exact)")
            result = validate_images(images, reference=refs[0], reference_var=var, max_mdb=args.max_mdb)
    else:
        if not args.scene:
            raise ConfigError("--images needs --reference images or a SCENE to render the path tracer on")
        from .validation import IndependentRuns

        h, w = images[0].shape[:2]
        scene = _load_scene(args.scene, args.defines, lambda m: print(f"warning: {m}", file=sys.stderr))
        ref_cfg = RenderConfig(method="pt", spp=args.ref_spp, frames=args.frames, width=w, height=h,
                               max_depth=args.max_depth, device=args.device)
        runs = args.ref_runs or len(images)
        what = f"the path tracer here, {runs} runs x {args.frames} frames x {args.ref_spp} spp"
        print(f"rendering the reference: {what}", file=sys.stderr)
        ref = IndependentRuns(scene, ref_cfg, runs, seed0=900_000, workers=args.workers or default_workers(),
                              ray=args.ray)
        result = validate_images(images, reference_images=list(ref.batches), max_mdb=args.max_mdb)
    print(f"validating {len(images)} images ({images[0].shape[1]}x{images[0].shape[0]}) against {what}",
          file=sys.stderr)
    _print_validation(result, args.max_mdb)
    print(f"verdict: {result.verdict}" + (f" ({result.reason})" if result.verdict == "inconclusive" else ""))
    if args.zmap:
        _write(args.zmap, write_image, result.zmap())
        print(f"wrote {args.zmap}")
    return {"pass": 0, "fail": 1, "inconclusive": 3}[result.verdict]


def _validate(args) -> int:
    from .image_io import write_image
    from .integrators import METHODS
    from .validation import validate

    if args.images:
        return _validate_images(args)
    if args.reference or args.reference_variance:
        raise ConfigError("--reference and --reference-variance go with --images")
    if not args.scene:
        raise ConfigError("give a SCENE to render, or --images to test")

    for option, n in (("--runs", args.runs), ("--ref-runs", args.ref_runs)):
        if n is not None and n < 2:
            raise ConfigError(f"{option} {n}: at least 2 independent runs are needed")
    if args.zmap:
        check_output(args.zmap, "--zmap", tuple(IMAGE_FORMATS))
    scene = _load_scene(args.scene, args.defines, lambda m: print(f"warning: {m}", file=sys.stderr))
    common = dict(frames=args.frames, width=args.width, height=args.height, device=args.device,
                  camera_motion=args.camera_motion, camera_speed=args.camera_speed)
    depth = args.max_depth
    fixed = getattr(METHODS.get(args.method), "FIXED_MAX_DEPTH", None)
    if depth is None and fixed is not None:
        depth = fixed
        if scene.max_depth != fixed:
            print(f"note: method '{args.method}' renders max_depth {fixed} only; both sides are compared at "
                  f"max_depth {fixed}, not the scene's {scene.max_depth}", file=sys.stderr)
    tested = RenderConfig(method=args.method, spp=args.spp, max_depth=depth, settings=dict(args.settings), **common)
    reference = RenderConfig(method="pt", spp=args.ref_spp, max_depth=depth, **common)
    print(f"validating {args.method} against pt on {args.scene}: {args.runs} runs x {args.frames} frames, "
          f"{args.width}x{args.height}, max_depth {depth if depth is not None else scene.max_depth}", file=sys.stderr)
    result = validate(scene, tested, args.runs, reference, args.ref_runs, max_mdb=args.max_mdb,
                      workers=args.workers or default_workers(), ray=args.ray)
    _print_validation(result, args.max_mdb)
    if result.tested.counters:
        print("counters over all runs: " + ", ".join(f"{k} {v}" for k, v in sorted(result.tested.counters.items())))
    print(f"verdict: {result.verdict}" + (f" ({result.reason})" if result.verdict == "inconclusive" else ""))
    if args.zmap:
        _write(args.zmap, write_image, result.zmap())
        print(f"wrote {args.zmap}")
    return {"pass": 0, "fail": 1, "inconclusive": 3}[result.verdict]


def _compare_tables(result, denoised: bool) -> list:
    """The terminal's tables: the error, and the error's structure (what a denoiser sees)."""
    from rich.markup import escape
    from rich.table import Table

    from .compare.structure import BLOCK_SIZES, TABLE_RADII

    def num(v, spec="{:.4g}"):
        return "-" if v is None else spec.format(v)

    errors = Table(title=f"{result.scene} {result.width}x{result.height}, {result.budget}; reference: "
                         f"{result.reference.source}")
    cols = ["method", "frames", "ms/frame", "relMSE per frame", "relMSE accumulated", "MAPE", "FLIP", "mean ratio (z)"]
    cols += ["denoised relMSE per frame", "denoised FLIP per frame"] if denoised else []
    for col in cols:
        errors.add_column(col, justify="left" if col == "method" else "right")
    shape = Table(title="error structure: correlation factor at block size B (1: independent pixels, B^2: "
                        "constant over blocks), radial correlation at r px (0: none), temporal correlation")
    for col in ["method"] + [f"factor B={b}" for b in BLOCK_SIZES] + [f"radial r={r}" for r in TABLE_RADII] \
            + ["temporal"]:
        shape.add_column(col, justify="left" if col == "method" else "right")
    for m in result.methods:
        x = m.metrics
        z = f" ({x['mean_z']:+.2f})" if x["mean_z"] is not None else ""
        errors.add_row(escape(m.label), str(m.frames), f"{x['ms_per_frame']:.1f}", num(x["relmse_frame"]),
                       num(x["relmse_accumulated"]), num(x["mape"]), num(x["flip"], "{:.4f}"),
                       f"{x['mean_ratio']:.4f}{z}",
                       *([num(x.get("relmse_denoised_frame")), num(x.get("flip_denoised_frame"), "{:.4f}")]
                         if denoised else []))
        radial = dict(zip(m.radial["radii"], m.radial["values"])) if m.radial else {}
        shape.add_row(escape(m.label), *[num(x["correlation_factor"][str(b)], "{:.2f}") for b in BLOCK_SIZES],
                      *[num(radial.get(r), "{:.3f}") for r in TABLE_RADII], num(x["temporal_correlation"], "{:.3f}"))
    return [errors, shape]


def _compare(args) -> int:
    from rich.console import Console
    from rich.markup import escape
    from rich.progress import BarColumn, Progress, TimeElapsedColumn

    from .compare import MethodSpec, compare

    console = Console(stderr=True, quiet=args.quiet)
    specs = [MethodSpec.parse(m) for m in args.methods]  # bad methods and settings: refused before any work
    if not specs:
        raise ConfigError("give at least one --method")
    if args.json:
        check_output(args.json, "--json", (".json",))
    if args.report:
        check_output_folder(args.report, "--report")
    tev = None
    if args.tev:
        from .viewer import connect_tev

        tev = connect_tev(args.tev)
    scene = _load_scene(args.scene, args.defines,
                        lambda m: console.print(f"[yellow]warning:[/] {escape(m)}", highlight=False, soft_wrap=True))
    with Progress("[progress.description]{task.description}", BarColumn(), "{task.percentage:>3.0f}%",
                  TimeElapsedColumn(), console=console, transient=True) as bar:
        tasks = {}

        def progress(label, fraction):
            if label not in tasks:
                tasks[label] = bar.add_task(label, total=1.0)
            bar.update(tasks[label], completed=fraction)

        result = compare(scene, specs, reference=args.reference, reference_spp=args.reference_spp,
                         equal_time=args.equal_time, equal_spp=args.equal_spp, frames=args.frames,
                         warmup=args.warmup, seed=args.seed, width=args.width, height=args.height,
                         max_depth=args.max_depth, device=args.device, progress=progress,
                         workers=args.workers, ray=args.ray, denoise=args.denoise, scene_file=args.scene,
                         defines=dict(args.defines), correlation_runs=args.correlation_runs,
                         match_frame_time=args.match_frame_time)
    for note in result.notes:
        console.print(f"note: {escape(note)}", highlight=False, soft_wrap=True)
    out = Console(width=None if sys.stdout.isatty() else 200)
    for table in _compare_tables(result, args.denoise):
        out.print(table)
    for line in result.headline:
        out.print(escape(line["text"]), highlight=False, soft_wrap=True)
    if tev is not None:
        from .viewer import send_to_tev

        send_to_tev(tev, "reference", result.reference.image.astype("float32"))
        for m in result.methods:
            send_to_tev(tev, m.label, m.image)
            if m.denoised is not None:
                send_to_tev(tev, m.label + " (last frame denoised)", m.denoised)
        tev.__exit__(None, None, None)
    if args.json:
        _write(args.json, _write_json, result.to_dict())
        console.print(f"wrote {escape(args.json)}", highlight=False)
    if args.report:
        from .compare.report import write_report

        index = write_report(result, args.report)
        console.print(f"wrote the report: {escape(index)}", highlight=False, soft_wrap=True)
    return 130 if result.interrupted else 0


def _sweep(args) -> int:
    from rich.console import Console
    from rich.markup import escape
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TimeElapsedColumn
    from rich.table import Table

    from .compare.sweep import parse_grid, sweep, write_sweep

    console = Console(stderr=True, quiet=args.quiet)
    points = parse_grid(args.grid, args.method)  # unknown settings and bad values: before any work
    check_output_folder(args.out, "--out")
    scene = _load_scene(args.scene, args.defines,
                        lambda m: console.print(f"[yellow]warning:[/] {escape(m)}", highlight=False, soft_wrap=True))
    with Progress("[progress.description]{task.description}", BarColumn(), MofNCompleteColumn(),
                  TimeElapsedColumn(), console=console, transient=True) as bar:
        task = bar.add_task("renders", total=len(points) * max(args.seeds, 1))
        result = sweep(scene, args.method, points, seeds=args.seeds, frames=args.frames, spp=args.spp,
                       warmup=args.warmup, reference=args.reference, reference_spp=args.reference_spp,
                       width=args.width, height=args.height, max_depth=args.max_depth, device=args.device,
                       workers=args.workers, ray=args.ray,
                       progress=lambda done, total: bar.update(task, completed=done))
    table = Table(title=f"{args.method} on {result.comparison.scene}: {result.comparison.budget}")
    for col in ("grid point", "relMSE per frame", "relMSE accumulated", "MAPE", "ms/frame"):
        table.add_column(col, justify="left" if col == "grid point" else "right")
    for e in result.summary:
        pm = lambda k: f"{e[k]:.4g} ± {e[k + '_std']:.2g}" if e["seeds"] > 1 else f"{e[k]:.4g}"  # noqa: E731
        table.add_row(escape(e["point"]), pm("relmse_frame"), pm("relmse_accumulated"), pm("mape"), pm("ms_per_frame"))
    Console(width=None if sys.stdout.isatty() else 200).print(table)
    index = write_sweep(result, args.out)
    console.print(f"wrote {escape(os.path.join(args.out, 'sweep.json'))}, sweep.csv and the report {escape(index)}",
                  highlight=False, soft_wrap=True)
    return 0


def _info() -> int:
    from . import __version__
    from .integrators import METHODS

    print(f"restir {__version__}\n\nmethods (--method NAME; settings with --set KEY=VALUE):")
    for name, cls in METHODS.items():
        print(f"  {name}: {cls.DESCRIPTION}")
        for key, default in cls.SETTINGS.items():
            value = str(default).lower() if isinstance(default, bool) else default
            print(f"    {key + '=' + str(value):<28} {cls.SETTINGS_DOC[key]}")
    print()
    print(_builtins_epilog())
    return 0


def main(argv=None) -> int:
    try:
        args = build_parser().parse_args(argv)
    except SystemExit as e:  # --help, --version (0) and one-line argument errors (2)
        return e.code if isinstance(e.code, int) else 0 if e.code is None else 2
    try:
        if args.command == "render":
            return _render(args)
        if args.command == "validate":
            return _validate(args)
        if args.command == "sweep":
            return _sweep(args)
        if args.command == "compare":
            return _compare(args)
        if args.command == "info":
            return _info()
    except (SceneError, ConfigError) as e:
        msg = e.message if isinstance(e, SceneError) else str(e)
        loc = f"{e.loc}: " if isinstance(e, SceneError) and e.loc else ""
        print(f"{loc}error: {msg}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130
    return 1
