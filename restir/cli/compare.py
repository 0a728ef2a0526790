"""`restir compare`: methods at equal time or equal samples against a reference: the error, its
structure (what a denoiser sees), a headline, JSON and the HTML report."""
from ..config import ConfigError
from .common import (add_command, check_output, check_output_folder, close_tev, console, defines_option, device_option,
                     fanout_options, finite_float, jitter_option, load_scene, open_tev, path_argument, progress_bar,
                     results_console, say, scene_argument, tev_option, write, write_json)


def add_parser(sub) -> None:
    c = add_command(sub, "compare", "compare methods at equal time or equal samples against a reference "
                    "(metrics, report)")
    scene_argument(c)
    c.add_argument("--method", dest="methods", action="append", default=[], metavar="NAME[:key=value,...]",
                   help="a method to compare, with its settings (spp=N: samples per pixel per frame); repeat "
                        "for each method, e.g. --method pt --method 'restir-di:spatial.neighbors=8'")
    c.add_argument("--reference", metavar="FILE", type=path_argument,
                   help="reference image (.exr, .npy, .png) of the compared size, or "
                   "'mitsuba': Mitsuba 3 at --reference-spp on the same XML (restir[reference]) (default: the path "
                   "tracer at --reference-spp; both cached under ~/.cache/restir or $RESTIR_CACHE)")
    c.add_argument("--reference-spp", type=int, default=1024, help="spp of the path-traced reference")
    budget = c.add_mutually_exclusive_group()
    budget.add_argument("--equal-time", type=finite_float, metavar="SECONDS",
                        help="every method renders frames for this wall time (compilation excluded)")
    budget.add_argument("--equal-spp", type=int, metavar="N", help="every method renders N samples per pixel")
    c.add_argument("--frames", type=int, default=16, help="frames per method when no budget is given")
    c.add_argument("--warmup", type=int, default=4, help="frames before the per-frame error is measured")
    c.add_argument("--seed", type=int, default=0, help="random seed")
    c.add_argument("--width", type=int, help="image width (default: the scene's)")
    c.add_argument("--height", type=int, help="image height (default: the scene's)")
    c.add_argument("--max-depth", type=int, help="max_depth of every method and the reference (default: the "
                   "scene's; 2 when restir-di is compared)")
    defines_option(c)
    device_option(c)
    jitter_option(c)
    c.add_argument("--report", metavar="DIR", type=path_argument,
                   help="write the HTML report (opens offline) into this folder")
    c.add_argument("--json", metavar="FILE", type=path_argument, help="write the metrics, timings and stats as JSON")
    c.add_argument("--quiet", action="store_true", help="no progress display")
    fanout_options(c, "the correlation runs, and the methods at equal samples or frames (equal time renders them "
                   "one after another)")
    c.add_argument("--denoise", action="store_true", help="also denoise the frames after the warm-up (all, or an "
                   "evenly spaced subset of 9-16) and the last frame with Open Image Denoise (albedo and normal "
                   "guides; needs restir[denoise]): per-frame denoised relMSE and FLIP, the images in the report")
    c.add_argument("--correlation-runs", type=int, default=8, metavar="K",
                   help="independent runs (warmup + 1 frames each) per method for the radial correlation; 0: none")
    c.add_argument("--no-frame-time-match", dest="match_frame_time", action="store_false",
                   help="at equal time, do not also render the path tracer at each other method's frame time "
                        "(the per-frame baseline of the headline)")
    tev_option(c, "the reference and every method's image")


def tables(result, denoised: bool) -> list:
    """The terminal's tables: the error, and the error's structure (what a denoiser sees)."""
    from rich.markup import escape
    from rich.table import Table

    from ..compare.structure import BLOCK_SIZES, TABLE_RADII

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


def run(args) -> int:
    from ..compare import CompareConfig, MethodSpec, compare

    con = console(args.quiet)
    specs = [MethodSpec.parse(m) for m in args.methods]  # bad methods and settings: refused before any work
    if not specs:
        raise ConfigError("give at least one --method")
    if args.json:
        check_output(args.json, "--json", (".json",))
    if args.report:
        check_output_folder(args.report, "--report")
    tev = open_tev(args.tev)
    scene = load_scene(args.scene, args.defines, con, args.missing_textures)
    config = CompareConfig(reference=args.reference, reference_spp=args.reference_spp, equal_time=args.equal_time,
                           equal_spp=args.equal_spp, frames=args.frames, warmup=args.warmup, seed=args.seed,
                           width=args.width, height=args.height, max_depth=args.max_depth, device=args.device,
                           denoise=args.denoise, correlation_runs=args.correlation_runs,
                           match_frame_time=args.match_frame_time, workers=args.workers, ray=args.ray,
                           scene_file=args.scene, defines=dict(args.defines), jitter=args.jitter)
    with progress_bar(con, "{task.percentage:>3.0f}%") as bar:
        tasks = {}

        def progress(label, fraction):
            if label not in tasks:
                tasks[label] = bar.add_task(label, total=1.0)
            bar.update(tasks[label], completed=fraction)

        result = compare(scene, specs, config, progress=progress)
    for note in result.notes:
        say(con, note, "note: ")
    out = results_console()
    for table in tables(result, args.denoise):
        out.print(table)
    for line in result.headline:
        say(out, line["text"])
    if tev is not None:
        from ..tev import send_to_tev

        send_to_tev(tev, "reference", result.reference.image.astype("float32"))
        for m in result.methods:
            send_to_tev(tev, m.label, m.image)
            if m.denoised is not None:
                send_to_tev(tev, m.label + " (last frame denoised)", m.denoised)
        close_tev(tev)
    if args.json:
        write(args.json, write_json, result.to_dict())
        say(con, f"wrote {args.json}")
    if args.report:
        from ..compare.report import write_report

        index = write_report(result, args.report)
        say(con, f"wrote the report: {index}")
    return 130 if result.interrupted else 0
