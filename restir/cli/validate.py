"""`restir validate`: a method tested for bias against the path tracer (independent runs, z-tests),
or images from any renderer tested against reference images or runs."""
import os
import sys

from .. import limits
from ..config import ConfigError, RenderConfig
from ..fanout import default_workers
from ..image_io import IMAGE_FORMATS
from .common import (DEFAULT_MAX_MDB, add_command, check_output, console, defines_option, device_option, fanout_options,
                     finite_float, fraction, jitter_option, key_value, load_scene, path_argument, scene_argument, write)

VERDICT_STATUS = {"pass": 0, "fail": 1, "inconclusive": 3}


def add_parser(sub) -> None:
    v = add_command(sub, "validate", "test a method for bias against the path tracer (independent runs, z-tests)")
    scene_argument(v, nargs="?", help="Mitsuba 3 XML file, pbrt-v4 file (.pbrt), glTF 2.0 file (.gltf, .glb) or builtin:NAME (listed below); not needed when "
                   "--images are tested against --reference images")
    v.add_argument("--method", default="restir-di", help="the method tested")
    v.add_argument("--images", metavar="GLOB", type=path_argument,
                   help="test these images instead of rendering: K >= 2 independent runs "
                   "of any renderer (quote the pattern, e.g. 'runs/*.exr'), against --reference, or against the "
                   "path tracer rendered here on SCENE (--ref-runs runs of --frames x --ref-spp at the images' size)")
    v.add_argument("--reference", metavar="GLOB", type=path_argument,
                   help="with --images: K' >= 2 independent reference runs, or one "
                   "converged image (taken as exact unless --reference-variance is given)")
    v.add_argument("--reference-variance", metavar="FILE", type=path_argument,
                   help="with one --reference image: the per-pixel variance "
                   "of its mean, an image of the same size")
    v.add_argument("--runs", type=int, default=32, help="independent runs K (fresh seed and history each)")
    v.add_argument("--frames", type=int, default=8, help="frames T per run; a run's statistic is its average")
    v.add_argument("--spp", type=int, default=1, help="samples per pixel per frame of the tested method")
    v.add_argument("--width", type=int, default=32, help="image width in pixels")
    v.add_argument("--height", type=int, default=32, help="image height in pixels")
    v.add_argument("--max-depth", type=int, help="depth of both sides (default: the method's, restir-di: 2, "
                   "or the scene's)")
    v.add_argument("--set", dest="settings", action="append", type=key_value, default=[], metavar="KEY=VALUE",
                   help="setting of the tested method")
    defines_option(v)
    v.add_argument("--ref-spp", type=int, default=4, help="path-tracer spp per frame of the reference runs")
    v.add_argument("--ref-runs", type=int, help="reference runs (default: --runs)")
    v.add_argument("--max-mdb", type=fraction, default=DEFAULT_MAX_MDB, metavar="BOUND",
                   help="largest minimum detectable bias (relative, 80%% power) a pass may have, as a fraction "
                        "(0.05) or a percentage (5%%); above it the verdict is inconclusive (exit 3)")
    v.add_argument("--camera-motion", default="none", choices=["none", "orbit", "dolly"],
                   help="scripted camera motion over the frames")
    v.add_argument("--camera-speed", type=finite_float, default=1.0, help="orbit: degrees per frame; dolly: scene "
                   "diagonals per frame")
    device_option(v)
    jitter_option(v)
    v.add_argument("--zmap", metavar="FILE", type=path_argument,
                   help="write the per-pixel z map here (.png, .exr, .npy)")
    fanout_options(v, "the independent runs")


def _glob_images(pattern: str, option: str, seen: dict | None = None) -> list:
    """The images the pattern matches, sorted by name. With `seen` ({digest: where}, shared by the
    calls for the runs and the reference), an image identical to one read before is refused:
    independent runs are never identical, and copies of one run would pass with no variance."""
    import glob
    import hashlib

    from ..image_io import read_image

    paths = sorted(glob.glob(os.path.expanduser(pattern)))
    if not paths:
        raise ConfigError(f"{option} {pattern}: no file matches")
    images = []
    for p in paths:
        try:
            images.append(read_image(p))
        except Exception as e:  # unreadable or not an image: name the file
            raise ConfigError(f"{option}: cannot read {p}: {e}") from None
        if seen is not None:
            digest = hashlib.sha256(images[-1].tobytes()).hexdigest()
            if digest in seen:
                raise ConfigError(f"{option} {p} is the same image as {seen[digest]}: independent runs (and a "
                                  "reference) are never identical")
            seen[digest] = f"{option} {p}"
    return images


def _report(result, args) -> int:
    """The per-channel tests, the detectable bias, the verdict and the z map; the exit status."""
    from ..image_io import write_image

    for channel, rep in zip("RGB", result.report.reports):
        print(f"{channel}: {rep}")
    print(f"minimum detectable bias (image level, 80% power): {100 * result.report.mdb:.2f}% "
          f"(a pass needs at most {100 * args.max_mdb:.3g}%, --max-mdb)")
    counters = getattr(result.tested, "counters", None)  # rendered runs count events; images do not
    if counters:
        print("counters over all runs: " + ", ".join(f"{k} {v}" for k, v in sorted(counters.items())))
    print(f"verdict: {result.verdict}" + (f" ({result.reason})" if result.verdict == "inconclusive" else ""))
    if args.zmap:
        write(args.zmap, write_image, result.zmap())
        print(f"wrote {args.zmap}")
    return VERDICT_STATUS[result.verdict]


def _validate_images(args) -> int:
    from ..validation import validate_images

    if args.zmap:
        check_output(args.zmap, "--zmap", tuple(IMAGE_FORMATS))
    if args.reference_variance and not args.reference:
        raise ConfigError("--reference-variance needs --reference")
    seen: dict = {}
    images = _glob_images(args.images, "--images", seen)
    if len(images) < 2:
        raise ConfigError(f"--images {args.images}: {len(images)} file; at least 2 independent runs are needed")
    if args.reference:
        refs = _glob_images(args.reference, "--reference", seen)
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
        from ..validation import IndependentRuns

        h, w = images[0].shape[:2]
        scene = load_scene(args.scene, args.defines, console(), args.missing_textures)
        ref_cfg = RenderConfig(method="pt", spp=args.ref_spp, frames=args.frames, width=w, height=h,
                               max_depth=args.max_depth, device=args.device, jitter=args.jitter)
        runs = args.ref_runs or len(images)
        what = f"the path tracer here, {runs} runs x {args.frames} frames x {args.ref_spp} spp"
        print(f"rendering the reference: {what}", file=sys.stderr)
        ref = IndependentRuns(scene, ref_cfg, runs, seed0=900_000, workers=args.workers or default_workers(),
                              ray=args.ray)
        result = validate_images(images, reference_images=list(ref.batches), max_mdb=args.max_mdb)
    print(f"validating {len(images)} images ({images[0].shape[1]}x{images[0].shape[0]}) against {what}",
          file=sys.stderr)
    return _report(result, args)


def run(args) -> int:
    from ..integrators import METHODS
    from ..validation import validate

    if args.images:
        return _validate_images(args)
    if args.reference or args.reference_variance:
        raise ConfigError("--reference and --reference-variance go with --images")
    if not args.scene:
        raise ConfigError("give a SCENE to render, or --images to test")

    for option, n in (("--runs", args.runs), ("--ref-runs", args.ref_runs)):
        problem = limits.runs_problem(option, n, 2) if n is not None else None
        if problem:
            raise ConfigError(problem + ": at least 2 independent runs are needed" if n < 2 else problem)
    if args.zmap:
        check_output(args.zmap, "--zmap", tuple(IMAGE_FORMATS))
    scene = load_scene(args.scene, args.defines, console(), args.missing_textures)
    common = dict(frames=args.frames, width=args.width, height=args.height, device=args.device,
                  camera_motion=args.camera_motion, camera_speed=args.camera_speed, jitter=args.jitter)
    depth = args.max_depth
    fixed = METHODS[args.method].FIXED_MAX_DEPTH if args.method in METHODS else None
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
    return _report(result, args)
