"""`restir sweep`: one method over a grid of settings and seeds, fanned out locally or on Ray,
with a table, JSON, CSV and a report."""
import os

from .common import (add_command, check_output_folder, console, defines_option, device_option, fanout_options,
                     jitter_option, load_scene, path_argument, progress_bar, results_console, say, scene_argument)


def add_parser(sub) -> None:
    s = add_command(sub, "sweep", "one method over a grid of settings and seeds, fanned out locally or on Ray")
    scene_argument(s)
    s.add_argument("--method", required=True, help="the method swept (restir info lists its settings)")
    s.add_argument("--grid", action="append", default=[], metavar="KEY=V1,V2,...",
                   help="a setting and its values (spp: samples per pixel per frame); repeat for more axes: "
                        "every combination is rendered")
    s.add_argument("--seeds", type=int, default=1, help="seeds per grid point (0 .. N-1)")
    s.add_argument("--frames", type=int, default=16, help="frames per render")
    s.add_argument("--spp", type=int, default=1, help="samples per pixel per frame (unless on the grid)")
    s.add_argument("--warmup", type=int, default=4, help="frames before the per-frame error is measured")
    s.add_argument("--reference", metavar="FILE", type=path_argument,
                   help="reference image (default: the path tracer at "
                   "--reference-spp, cached)")
    s.add_argument("--reference-spp", type=int, default=1024, help="spp of the path-traced reference")
    s.add_argument("--width", type=int, help="image width (default: the scene's)")
    s.add_argument("--height", type=int, help="image height (default: the scene's)")
    s.add_argument("--max-depth", type=int, help="max_depth (default: the scene's)")
    defines_option(s)
    device_option(s)
    jitter_option(s)
    s.add_argument("--out", default="out/sweep", metavar="DIR", type=path_argument,
                   help="writes DIR/sweep.json, DIR/sweep.csv and "
                   "the report DIR/report/index.html")
    s.add_argument("--quiet", action="store_true", help="no progress display")
    fanout_options(s, "the renders")


def run(args) -> int:
    from rich.markup import escape
    from rich.progress import MofNCompleteColumn
    from rich.table import Table

    from ..compare.sweep import parse_grid, sweep, write_sweep

    con = console(args.quiet)
    points = parse_grid(args.grid, args.method)  # unknown settings and bad values: before any work
    check_output_folder(args.out, "--out")
    scene = load_scene(args.scene, args.defines, con, args.missing_textures)
    with progress_bar(con, MofNCompleteColumn()) as bar:
        task = bar.add_task("renders", total=len(points) * max(args.seeds, 1))
        result = sweep(scene, args.method, points, seeds=args.seeds, frames=args.frames, spp=args.spp,
                       warmup=args.warmup, reference=args.reference, reference_spp=args.reference_spp,
                       width=args.width, height=args.height, max_depth=args.max_depth, device=args.device,
                       workers=args.workers, ray=args.ray, jitter=args.jitter,
                       progress=lambda done, total: bar.update(task, completed=done))
    table = Table(title=f"{args.method} on {result.comparison.scene}: {result.comparison.budget}")
    for col in ("grid point", "relMSE per frame", "relMSE accumulated", "MAPE", "ms/frame"):
        table.add_column(col, justify="left" if col == "grid point" else "right")
    for e in result.summary:
        pm = lambda k: f"{e[k]:.4g} ± {e[k + '_std']:.2g}" if e["seeds"] > 1 else f"{e[k]:.4g}"  # noqa: E731
        table.add_row(escape(e["point"]), pm("relmse_frame"), pm("relmse_accumulated"), pm("mape"), pm("ms_per_frame"))
    results_console().print(table)
    index = write_sweep(result, args.out)
    say(con, f"wrote {os.path.join(args.out, 'sweep.json')}, sweep.csv and the report {index}")
    return 0
