"""Command line: `restir render SCENE ...` (the contract in DESIGN.md "Command line").

Parses arguments into a RenderConfig and calls the API; user errors print one line
(`file:line: error: ...`) and exit with status 2, never a traceback.
"""
import argparse
import json
import os
import sys
import warnings

from .config import ConfigError, RenderConfig
from .scene.builtin import BUILTINS
from .scene.errors import SceneError, SceneWarning


def _key_value(text: str) -> tuple[str, str]:
    if "=" not in text:
        raise argparse.ArgumentTypeError(f"expected name=value, got '{text}'")
    k, v = text.split("=", 1)
    return k.strip(), v.strip()


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="restir", description="Research renderer for resampled path tracing.")
    sub = ap.add_subparsers(dest="command", required=True)
    r = sub.add_parser("render", help="render a scene")
    r.add_argument("scene", help=f"Mitsuba 3 XML file or builtin:NAME ({', '.join(BUILTINS)})")
    r.add_argument("--method", default="pt", help="pt (path tracer) or restir-di (direct light: emission plus one "
                   "bounce; settings with --set, listed in docs/restir_di.md)")
    r.add_argument("--spp", type=int, help="samples per pixel per frame (default: the scene's)")
    r.add_argument("--frames", type=int, default=1, help="frames to render and average")
    r.add_argument("--width", type=int)
    r.add_argument("--height", type=int)
    r.add_argument("--max-depth", type=int, help="Mitsuba's max_depth (-1: unbounded)")
    r.add_argument("--seed", type=int, default=0)
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
    r.add_argument("-o", "--output", default="out/render.exr", help="EXR output (default out/render.exr)")
    r.add_argument("--png", help="also write a tonemapped sRGB PNG")
    r.add_argument("--exposure", type=float, default=0.0, help="PNG exposure in stops")
    r.add_argument("--stats", help="write the stats JSON here")
    r.add_argument("--quiet", action="store_true", help="no progress bar or timing table")

    v = sub.add_parser("validate", help="test a method for bias against the path tracer (independent runs, z-tests)")
    v.add_argument("scene")
    v.add_argument("--method", default="restir-di")
    v.add_argument("--runs", type=int, default=32, help="independent runs K (fresh seed and history each)")
    v.add_argument("--frames", type=int, default=8, help="frames T per run; a run's statistic is its average")
    v.add_argument("--spp", type=int, default=1)
    v.add_argument("--width", type=int, default=32)
    v.add_argument("--height", type=int, default=32)
    v.add_argument("--max-depth", type=int, help="default: the method's (restir-di: 2) or the scene's")
    v.add_argument("--set", dest="settings", action="append", type=_key_value, default=[], metavar="KEY=VALUE")
    v.add_argument("-D", dest="defines", action="append", type=_key_value, default=[], metavar="NAME=VALUE")
    v.add_argument("--ref-spp", type=int, default=4, help="path-tracer spp per frame of the reference runs")
    v.add_argument("--ref-runs", type=int, help="reference runs (default: --runs)")
    v.add_argument("--camera-motion", default="none", choices=["none", "orbit", "dolly"])
    v.add_argument("--camera-speed", type=float, default=1.0)
    v.add_argument("--device", default="cpu")
    v.add_argument("--zmap", help="write the per-pixel z map here (PNG or EXR)")
    return ap


def _render(args) -> int:
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TimeElapsedColumn, TimeRemainingColumn
    from rich.table import Table

    from . import api
    from .image_io import write_exr, write_png

    console = Console(stderr=True, quiet=args.quiet)
    config = RenderConfig(method=args.method, spp=args.spp, frames=args.frames, width=args.width,
                          height=args.height, max_depth=args.max_depth, seed=args.seed, device=args.device, tracer=args.tracer,
                          camera_motion=args.camera_motion, camera_speed=args.camera_speed,
                          settings=dict(args.settings))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", SceneWarning)
        scene = api.load_scene(args.scene, dict(args.defines) or None)
    for w in caught:
        console.print(f"[yellow]warning:[/] {w.message}", highlight=False)
    with Progress("[progress.description]{task.description}", BarColumn(), MofNCompleteColumn(),
                  TimeElapsedColumn(), TimeRemainingColumn(), console=console, transient=True) as bar:
        task = bar.add_task(f"{config.method} frames", total=config.frames)
        result = api.render(scene, config, progress=lambda done, total: bar.update(task, completed=done))
    write_exr(args.output, result.image)
    written = [args.output]
    if args.png:
        write_png(args.png, result.image, args.exposure)
        written.append(args.png)
    if args.stats:
        os.makedirs(os.path.dirname(os.path.abspath(args.stats)), exist_ok=True)
        with open(args.stats, "w") as f:
            json.dump(result.stats, f, indent=2, default=str)
        written.append(args.stats)
    st = result.stats
    table = Table(title=f"{st['method']} on {st['scene']} ({st['width']}x{st['height']}, "
                        f"{st['spp_per_frame']} spp x {st['frames']} frames, {st['device']}, {st['tracer']})")
    table.add_column("stage")
    table.add_column("ms per frame", justify="right")
    for name, s in st["stages"].items():
        table.add_row(name, f"{s['total_ms'] / st['frames']:.1f}")
    table.add_row("total", f"{st['ms_per_frame']:.1f}")
    console.print(table)
    console.print(f"{st['rays_per_second'] / 1e6:.2f} Mrays/s, "
                  f"{st['bytes_per_pixel']['total']:.0f} bytes/pixel in render buffers")
    for path in written:
        console.print(f"wrote {path}")
    return 0


def _validate(args) -> int:
    from . import api
    from .image_io import write_image
    from .validation import validate

    scene = api.load_scene(args.scene, dict(args.defines) or None)
    common = dict(frames=args.frames, width=args.width, height=args.height, device=args.device,
                  camera_motion=args.camera_motion, camera_speed=args.camera_speed)
    depth = args.max_depth
    if depth is None and args.method == "restir-di":
        depth = 2
    tested = RenderConfig(method=args.method, spp=args.spp, max_depth=depth, settings=dict(args.settings), **common)
    reference = RenderConfig(method="pt", spp=args.ref_spp, max_depth=depth, **common)
    print(f"validating {args.method} against pt on {args.scene}: {args.runs} runs x {args.frames} frames, "
          f"{args.width}x{args.height}", file=sys.stderr)
    result = validate(scene, tested, args.runs, reference, args.ref_runs)
    for channel, rep in zip("RGB", result.report.reports):
        print(f"{channel}: {rep}")
    print(f"minimum detectable bias (image level, 80% power): {100 * result.report.mdb:.2f}%")
    if result.tested.counters:
        print("counters over all runs: " + ", ".join(f"{k} {v}" for k, v in sorted(result.tested.counters.items())))
    if result.report.mdb > 0.05:
        print("note: 'pass' only rules out biases above that; raise --runs, --frames or --spp", file=sys.stderr)
    print(f"verdict: {result.verdict}")
    if args.zmap:
        write_image(args.zmap, result.zmap())
        print(f"wrote {args.zmap}")
    return {"pass": 0, "fail": 1, "inconclusive": 3}[result.verdict]


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    try:
        if args.command == "render":
            return _render(args)
        if args.command == "validate":
            return _validate(args)
    except (SceneError, ConfigError) as e:
        msg = e.message if isinstance(e, SceneError) else str(e)
        loc = f"{e.loc}: " if isinstance(e, SceneError) and e.loc else ""
        print(f"{loc}error: {msg}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130
    return 1
