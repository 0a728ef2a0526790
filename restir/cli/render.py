"""`restir render SCENE`: one method's frames, averaged, written as an image (and AOVs, frames,
stats), with a progress bar and a per-stage timing table."""
import os
import sys

from ..config import ConfigError, RenderConfig, parse_aovs
from ..image_io import IMAGE_FORMATS, LDR_FORMATS
from .common import (add_command, check_output, check_output_folder, close_tev, console, defines_option, device_option,
                     finite_float, jitter_option, key_value, load_scene, open_tev, path_argument, progress_bar, say,
                     scene_argument, tev_option, write, write_json)


def add_parser(sub) -> None:
    r = add_command(sub, "render", "render a scene")
    scene_argument(r)
    r.add_argument("--method", default="pt", help="pt (path tracer), restir-di (direct light: emission plus one "
                   "bounce), restir-pt (path reuse) or suffix-restir (conditional suffix reuse with a final "
                   "gather); settings with --set, listed by `restir info`")
    r.add_argument("--spp", type=int, help="samples per pixel per frame (default: the scene's)")
    r.add_argument("--frames", type=int, default=1, help="frames to render and average")
    r.add_argument("--width", type=int, help="image width in pixels (default: the scene's)")
    r.add_argument("--height", type=int, help="image height in pixels (default: the scene's)")
    r.add_argument("--max-depth", type=int, help="Mitsuba's max_depth, -1: unbounded (default: the scene's; "
                   "restir-di computes 2 only; restir-pt and suffix-restir up to 255, -1 as 64)")
    r.add_argument("--seed", type=int, default=0, help="random seed")
    device_option(r)
    jitter_option(r)
    r.add_argument("--tracer", default="auto", choices=["auto", "embree", "warp"],
                   help="CPU ray tracer (auto: Embree if available; CUDA always uses Warp's BVH)")
    r.add_argument("--camera-motion", default="none", choices=["none", "orbit", "dolly"],
                   help="scripted camera motion over the frames (the scene stays static)")
    r.add_argument("--camera-speed", type=finite_float, default=1.0,
                   help="orbit: degrees per frame; dolly: scene diagonals per frame")
    defines_option(r)
    r.add_argument("--set", dest="settings", action="append", type=key_value, default=[], metavar="KEY=VALUE",
                   help="method setting, e.g. strategy=nee")
    r.add_argument("-o", "--output", metavar="FILE", type=path_argument,
                   help="the image, format by extension: .exr (linear float), .png or .jpg (tonemapped sRGB, "
                        "with --exposure), .npy (float32 linear, H x W x 3) (default: <scene name>.exr in the "
                        "current folder)")
    r.add_argument("--png", metavar="FILE", type=path_argument, help="also write a tonemapped sRGB PNG (or .jpg)")
    r.add_argument("--exposure", type=finite_float, default=0.0, help="exposure in stops of the tonemapped images")
    r.add_argument("--stats", metavar="FILE", type=path_argument, help="write the stats JSON here")
    r.add_argument("--write-frames", metavar="DIR", type=path_argument,
                   help="also write every frame's image as DIR/frame_0000.exr, frame_0001.exr, ...")
    r.add_argument("--quiet", action="store_true", help="no progress bar, timing table or notes")
    r.add_argument("--aov", metavar="NAMES", help="also write these layers into the EXR: albedo, normal (comma-"
                   "separated; channels albedo.R/G/B, normal.X/Y/Z, as Mitsuba's aov integrator), for denoisers")
    tev_option(r, "the image (and AOVs)")


def default_output(scene_spec: str) -> str:
    """<scene name>.exr in the current folder, as Mitsuba names it (builtin name or XML file stem)."""
    if scene_spec.startswith("builtin:"):
        name = scene_spec.split(":", 1)[1]
    else:
        name = os.path.splitext(os.path.basename(scene_spec))[0]
    return (name or "render") + ".exr"


def run(args) -> int:
    from rich.progress import MofNCompleteColumn, TimeRemainingColumn
    from rich.table import Table

    from .. import api
    from ..image_io import write_exr, write_image, write_png

    con = console(args.quiet)
    aovs = parse_aovs(args.aov) if args.aov else ()
    config = RenderConfig(method=args.method, spp=args.spp, frames=args.frames, width=args.width,
                          height=args.height, max_depth=args.max_depth, seed=args.seed, device=args.device,
                          tracer=args.tracer, camera_motion=args.camera_motion, camera_speed=args.camera_speed,
                          settings=dict(args.settings), keep_frames=bool(args.write_frames), aovs=aovs,
                          jitter=args.jitter)
    config.validate()
    output = args.output or default_output(args.scene)
    check_output(output, "-o" if args.output else "output", tuple(IMAGE_FORMATS))
    if aovs and not output.lower().endswith(".exr"):
        raise ConfigError(f"--aov writes layers of an EXR; the output {output} is not .exr")
    tev = open_tev(args.tev)
    if args.png:
        check_output(args.png, "--png", LDR_FORMATS)
    if args.stats:
        check_output(args.stats, "--stats")
    if args.write_frames:
        check_output_folder(args.write_frames, "--write-frames")

    scene = load_scene(args.scene, args.defines, con, args.missing_textures)
    with progress_bar(con, MofNCompleteColumn(), TimeRemainingColumn()) as bar:
        task = bar.add_task(f"{config.method} frames", total=config.frames)
        try:
            result = api.render(scene, config, progress=lambda done, total: bar.update(task, completed=done),
                                on_compile=lambda: con.print("compiling kernels (once per configuration; "
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
        write(output, write_exr, result.image, result.aovs)
    else:
        write(output, write_image, result.image, args.exposure)
    written = [output]
    if tev is not None:
        from ..tev import send_to_tev

        send_to_tev(tev, f"{result.stats['method']} {result.stats['scene']}", result.image, result.aovs)
        close_tev(tev)
    if args.png:
        write(args.png, write_png, result.image, args.exposure)
        written.append(args.png)
    if args.write_frames:
        for i, frame in enumerate(result.frame_images):
            write(os.path.join(args.write_frames, f"frame_{i:04d}.exr"), write_exr, frame)
        written.append(os.path.join(args.write_frames, f"frame_0000.exr ... frame_{len(result.frame_images) - 1:04d}.exr"))
    if args.stats:
        write(args.stats, write_json, result.stats)
        written.append(args.stats)
    st = result.stats
    for note in st.get("notes", []):
        say(con, note, "note: ")
    table = Table(title=f"{st['method']} on {st['scene']} ({st['width']}x{st['height']}, "
                        f"{st['spp_per_frame']} spp x {st['frames']} frames, max_depth {st['max_depth']}, "
                        f"{st['device']}, {st['tracer']})")
    table.add_column("stage")
    table.add_column("ms per frame", justify="right")
    for name, s in st["stages"].items():
        table.add_row(name, f"{s['total_ms'] / st['frames']:.1f}")
    table.add_row("total", f"{st['ms_per_frame']:.1f}")
    con.print(table)
    con.print(f"{st['rays_per_second'] / 1e6:.2f} Mrays/s, "
              f"{st['bytes_per_pixel']['total']:.0f} bytes/pixel in render buffers")
    for path in written:
        say(con, f"wrote {path}")
    return 130 if interrupted else 0
