"""The headline measurements in one command, into one JSON: benchmarks/results/results.json, from
which `python -m docgen.results` writes docs/results.md and the README's status table.

    make results                # .venv/bin/python benchmarks/results_suite.py
    make results QUICK=1        # --quick: smaller images, fewer frames and seconds
    .venv/bin/python benchmarks/results_suite.py --only equal-time --scenes veach-ajar   # one part

What it measures, each with the command line that reproduces it (in the JSON):

- cost: each method's frame time over a 1-spp path-tracer frame at the same max_depth (ReSTIR DI
  computes max_depth 2 only, so its path tracer renders max_depth 2 too) and its bytes per
  pixel, on builtin:cornell-box at 512x512 (--quick: 256x256), max_depth 8. The methods
  alternate within each round (A B C D E, A B C D E) so that the machine's load hits all of them;
  each render times the frames after its first (which compiles nothing, the kernels are loaded
  before, but traces the first frame's extra rays) and keeps the median.
- equal-time: `restir compare` at equal time with --denoise on the indirect room, the glossy
  Cornell box, Veach Ajar and Modern Hall (the shared scenes veach-ajar and staircase2, from
  $RESTIR_SCENES or ../shared/scenes; skipped with a note when absent), the path tracer, ReSTIR
  PT and Suffix ReSTIR at each scene's own max_depth and aspect. The command runs in this
  process (restir.cli.main), so the kernels load once.
- many-lights: ReSTIR DI on builtin:many-lights with the emitters hidden (lighting only), its
  defaults and without reuse (temporal=false, spatial.rounds=0), against the path tracer, through
  restir.compare (the command line cannot hide a builtin's emitters).
- many-delta-lights: the same on builtin:many-delta-lights, the room lit by 300 point and spot
  lights (nothing to hide: a delta light is never seen).
- mitsuba: the path tracer against Mitsuba 3 (benchmarks/bench_pt_vs_mitsuba.py on the shared
  Cornell box) where the `mitsuba` package is installed; "not installed" otherwise.
- loads: restir.load_scene and the upload to the device (the BVH and Embree builds) for every
  shared scene and every builtin.
- view: `restir view`'s render loop without a browser (benchmarks/bench_view.py): ReSTIR PT on
  builtin:cornell-box at 256x256 with the camera still, and at the moving size with it turning,
  in frames per second with the tonemapping and the JPEG the page receives.
- verdicts: the slow tier's matrix verdicts as recorded by a run with
  RESTIR_RECORD_VERDICTS=benchmarks/results/verdicts.json (tests/helpers.py); "not recorded"
  when that file is missing. Nothing here runs the slow tier.

Progress goes to stderr; the compare commands' tables to out/results_suite/*.log. The JSON is
written to a temporary file and renamed at the end, so a Ctrl-C leaves the previous one intact.
With --only the JSON goes to out/results_suite/<parts>.json (or --out) and the pages are left
alone.
"""
import argparse
import contextlib
import datetime
import importlib.util
import json
import math
import os
import platform
import shlex
import statistics
import subprocess
import sys
import time
import warnings

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

RESULTS = os.path.join("benchmarks", "results", "results.json")
VERDICTS = os.path.join("benchmarks", "results", "verdicts.json")
LOGS = os.path.join("out", "results_suite")
PARTS = ("cost", "equal-time", "many-lights", "many-delta-lights", "mitsuba", "loads", "view", "verdicts")
PYTHON = ".venv/bin/python"
RESTIR = ".venv/bin/restir"

SIZES = {
    "default": {"cost_size": 512, "cost_timed_frames": 4, "cost_rounds": 2, "cost_max_depth": 8,
                "lines": 128, "seconds": 3.0, "reference_spp": 1024, "warmup": 4,
                "many_lights_size": 128, "mitsuba_size": 256, "mitsuba_spp": 4, "mitsuba_rounds": 2,
                "load_repeats": 3, "view_size": 256, "view_seconds": 10.0},
    "quick": {"cost_size": 256, "cost_timed_frames": 2, "cost_rounds": 2, "cost_max_depth": 8,
              "lines": 64, "seconds": 1.0, "reference_spp": 256, "warmup": 4,
              "many_lights_size": 64, "mitsuba_size": 128, "mitsuba_spp": 1, "mitsuba_rounds": 1,
              "load_repeats": 1, "view_size": 128, "view_seconds": 3.0},
}
COST_SCENE = "builtin:cornell-box"
# (method, max_depth): the path tracer at each depth first; every other method's ratio is to the
# path tracer at its depth in the same round
COST_SIDES = [("pt", None), ("restir-pt", None), ("suffix-restir", None), ("pt", 2), ("restir-di", 2)]
EQUAL_TIME_SCENES = [  # (name, title, builtin or shared scene folder)
    ("indirect-room", "Indirect room", "builtin:indirect-room"),
    ("cornell-box-glossy", "Glossy Cornell box", "builtin:cornell-box-glossy"),
    ("veach-ajar", "Veach Ajar", "veach-ajar"),
    ("staircase2", "Modern Hall", "staircase2"),
    ("crown", "Crown (pbrt-v4)", "pbrt:crown/crown.pbrt"),
]
EQUAL_TIME_METHODS = ["pt", "restir-pt", "suffix-restir"]
NO_REUSE = "restir-di:temporal=false,spatial.rounds=0"
MANY_LIGHTS_METHODS = ["pt", "restir-di", NO_REUSE]

_T0 = time.perf_counter()


def log(text: str) -> None:
    t = time.perf_counter() - _T0
    print(f"[results {int(t // 60):2d}:{int(t % 60):02d}] {text}", file=sys.stderr, flush=True)


# ------------------------------------------------------------------ where and what
def scenes_dir() -> str | None:
    value = os.environ.get("RESTIR_SCENES", "").strip()
    path = os.path.expanduser(value) if value else os.path.join(ROOT, "..", "shared", "scenes")
    return os.path.normpath(path) if os.path.isdir(path) else None


def shared_scene(name: str) -> str | None:
    root = scenes_dir()
    path = os.path.join(root, name, "scene.xml") if root else None
    return path if path and os.path.isfile(path) else None


def pbrt_scene(rel: str) -> str | None:
    """A pbrt-v4 scene from the folder RESTIR_PBRT_SCENES names: a checkout of
    w3ntao/pbrt-minus-scenes, whose Crown has all its files (docs/guide/pbrt.md)."""
    root = os.path.expanduser(os.environ.get("RESTIR_PBRT_SCENES", "").strip() or os.path.join(ROOT, "..", "pbrt-scenes"))
    path = os.path.join(root, rel)
    return os.path.normpath(path) if os.path.isfile(path) else None


def shown_path(path: str) -> str:
    """A path as a command line run from the repository root would name it."""
    rel = os.path.relpath(path, ROOT)
    return rel if not rel.startswith(os.pardir + os.sep + os.pardir) else path


def git(*args) -> str:
    try:
        return subprocess.run(["git", *args], cwd=ROOT, capture_output=True, text=True, timeout=60).stdout
    except (OSError, subprocess.SubprocessError):
        return ""


def machine() -> dict:
    import warp

    cpu = platform.processor() or platform.machine()
    mem = None
    with contextlib.suppress(OSError):
        with open("/proc/cpuinfo") as f:
            cpu = next((line.split(":", 1)[1].strip() for line in f if line.startswith("model name")), cpu)
    with contextlib.suppress(OSError, StopIteration, ValueError):
        with open("/proc/meminfo") as f:
            kb = next(int(line.split()[1]) for line in f if line.startswith("MemTotal"))
        mem = round(kb / 2 ** 20, 1)
    from importlib import metadata

    packages = {}
    for name in ("numpy", "embreex", "pyoidn", "mitsuba"):
        with contextlib.suppress(metadata.PackageNotFoundError):
            packages[name] = metadata.version(name)
    return {"cpu": cpu, "cores": os.cpu_count(),
            "cores_usable": len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count(),
            "memory_gib": mem, "os": platform.platform(), "python": platform.python_version(),
            "warp": warp.__version__, "packages": packages,
            "restir_cpu_threads": os.environ.get("RESTIR_CPU_THREADS")}


def commit() -> dict:
    changed = [line[3:] for line in git("status", "--porcelain", "--untracked-files=no").splitlines() if line]
    return {"hash": git("rev-parse", "HEAD").strip(), "dirty": bool(changed), "dirty_count": len(changed),
            "dirty_paths": changed[:40]}


def suite_command(args, parts=None, extra=()) -> str:
    """The command line that reproduces `parts` of this run (all of it without parts)."""
    words = [PYTHON, "benchmarks/results_suite.py"] + (["--quick"] if args.quick else [])
    if parts:
        words += ["--only", *parts]
    return shlex.join(words + list(extra))


def clean(x):
    """JSON-safe: NaN and infinities as null, tuples as lists, numpy scalars as numbers."""
    if isinstance(x, dict):
        return {str(k): clean(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [clean(v) for v in x]
    if hasattr(x, "item") and not isinstance(x, (str, bytes)):
        x = x.item()
    if isinstance(x, float) and not math.isfinite(x):
        return None
    return x


# ------------------------------------------------------------------ (a) frame cost and memory
def part_cost(args, size) -> dict:
    import restir
    from restir.api import make_integrator, sized_scene

    n, frames, rounds = size["cost_size"], size["cost_timed_frames"], size["cost_rounds"]
    depth = size["cost_max_depth"]
    scene = restir.load_scene(COST_SCENE)

    def config(method, max_depth, seed):
        return restir.RenderConfig(method=method, spp=1, width=n, height=n, seed=seed,
                                   max_depth=max_depth or depth)

    def timed(method, max_depth, seed):
        cfg = config(method, max_depth, seed)
        integ = make_integrator(sized_scene(scene, cfg), cfg)
        integ.render_frame(0)  # the first frame: no history yet, the emission rays at every pixel
        ms = []
        for f in range(1, frames + 1):
            t = time.perf_counter()
            integ.render_frame(f)
            ms.append(1e3 * (time.perf_counter() - t))
        return statistics.median(ms), integ.stats()["bytes_per_pixel"]

    for method, max_depth in COST_SIDES:  # load (compile) every kernel first
        log(f"cost: loading {method}'s kernels")
        cfg = config(method, max_depth, 0)
        make_integrator(sized_scene(scene, cfg), cfg).render_frame(0)
    ms = {side: [] for side in COST_SIDES}
    bpp = {}
    for rep in range(rounds):
        for side in COST_SIDES:
            log(f"cost: round {rep + 1}/{rounds}, {side[0]} (max_depth {side[1] or depth}), {n}x{n}")
            t, b = timed(*side, seed=rep)
            ms[side].append(t)
            bpp[side] = b
    out = {}
    for method, max_depth in COST_SIDES:
        key = method if max_depth is None else f"{method}@{max_depth}"
        base = ms[("pt", max_depth)]
        ratios = [a / b for a, b in zip(ms[(method, max_depth)], base)]
        out[key] = {"method": method, "max_depth": max_depth or depth, "ms_per_frame": ms[(method, max_depth)],
                    "pt_ms_per_frame": base, "ratio": ratios, "ratio_median": statistics.median(ratios),
                    "bytes_per_pixel": bpp[(method, max_depth)].get("total"),
                    "bytes_per_pixel_by_buffer": {k: v for k, v in bpp[(method, max_depth)].items() if k != "total"}}
    return {"command": suite_command(args, ["cost"]), "scene": COST_SCENE, "width": n, "height": n,
            "max_depth": depth, "timed_frames": frames, "rounds": rounds, "methods": out}


# ------------------------------------------------------------------ (b), (c) equal time
def summarize_comparison(d: dict) -> dict:
    """The parts of a Comparison's JSON (restir compare --json) the tables need."""
    heads = {h["method"]: h for h in d.get("headline", [])}
    methods = []
    for m in d["methods"]:
        x = m["metrics"]
        h = heads.get(m["label"])
        methods.append({
            "label": m["label"], "method": m["method"], "spp": m["spp"], "frames": m["frames"],
            "ms_per_frame": x["ms_per_frame"], "relmse_frame": x["relmse_frame"],
            "relmse_denoised_frame": x.get("relmse_denoised_frame"), "relmse_accumulated": x["relmse_accumulated"],
            "correlation_factor_8": x["correlation_factor"].get("8"), "temporal_correlation": x["temporal_correlation"],
            "mean_ratio": x["mean_ratio"], "mean_z": x["mean_z"], "max_depth": m["stats"].get("max_depth"),
            "bytes_per_pixel": m["stats"].get("bytes_per_pixel", {}).get("total"),
            "frame_time_of": m.get("frame_time_of", []),
            "against_pt": None if h is None else {
                "spp": h["baseline_spp"], "basis": h["basis"], "pt_ms_per_frame": h["ms_per_frame"][1],
                "raw_frame": h["raw_frame"], "denoised_frame": h["denoised_frame"], "accumulated": h["accumulated"]}})
    return {"width": d["width"], "height": d["height"], "budget": d["budget"], "warmup": d["warmup"],
            "reference": d["reference"].split(" (")[0], "reference_relmse": d.get("reference_relmse"),
            "frame_time_fit": d.get("frame_time_fit"), "interrupted": d.get("interrupted", False),
            "methods": methods}


def run_cli(argv: list, log_name: str) -> int:
    """`restir ARGV` in this process (restir.cli.main), its tables into out/results_suite/LOG_NAME."""
    from restir.cli import main

    os.makedirs(LOGS, exist_ok=True)
    with open(os.path.join(LOGS, log_name), "w") as f, contextlib.redirect_stdout(f):
        code = main(argv)
    if code == 130:
        raise KeyboardInterrupt
    return code


def part_equal_time(args, size) -> dict:
    import restir

    rows = []
    for name, title, spec in EQUAL_TIME_SCENES:
        if args.scenes and name not in args.scenes:
            continue
        if spec.startswith("pbrt:"):
            path = pbrt_scene(spec[5:])
            where, var = os.environ.get("RESTIR_PBRT_SCENES") or "../pbrt-scenes", "RESTIR_PBRT_SCENES"
        else:
            path = spec if spec.startswith("builtin:") else shared_scene(spec)
            where, var = os.environ.get("RESTIR_SCENES") or "../shared/scenes", "RESTIR_SCENES"
        if path is None:
            rows.append({"name": name, "title": title, "skipped": f"the scene {spec} is not in {where} "
                         f"(set {var} to the folder holding it)"})
            log(f"equal time: {title} skipped (no {spec} in {where})")
            continue
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            cam = restir.load_scene(path).camera
        h = size["lines"]
        w = int(round(h * cam.width / cam.height / 2)) * 2
        json_out = os.path.join(LOGS, f"equal_time_{name}.json")
        report = os.path.join(LOGS, f"report_{name}")
        shown = f"$RESTIR_PBRT_SCENES/{spec[5:]}" if spec.startswith("pbrt:") else shown_path(path)
        argv = ["compare", path if path.startswith("builtin:") else shown]
        for m in EQUAL_TIME_METHODS:
            argv += ["--method", m]
        argv += ["--equal-time", f"{size['seconds']:g}", "--width", str(w), "--height", str(h),
                 "--reference-spp", str(size["reference_spp"]), "--warmup", str(size["warmup"]), "--seed", "0",
                 "--denoise", "--correlation-runs", "0", "--quiet", "--json", json_out, "--report", report]
        log(f"equal time: {title} {w}x{h}, {size['seconds']:g} s a method: {RESTIR} {shlex.join(argv)}")
        code = run_cli([a if a != shown else path for a in argv], f"equal_time_{name}.log")
        if code != 0:
            raise SystemExit(f"restir compare failed on {title} (exit {code}); see {LOGS}/equal_time_{name}.log")
        with open(json_out) as f:
            rows.append({"name": name, "title": title, "scene": argv[1], "command": shlex.join([RESTIR, *argv]),
                         "gallery": gallery_image(report, name), **summarize_comparison(json.load(f))})
    return {"methods": EQUAL_TIME_METHODS, "seconds": size["seconds"], "lines": size["lines"], "scenes": rows}


GALLERY_GAP = 4  # px of white between the gallery's images


def gallery_image(report: str, name: str) -> dict:
    """The gallery image of one equal-time scene, from the images `restir compare --report` wrote:
    the reference, then each method's last frame (top row) and the same frame through Open Image
    Denoise (bottom row), tonemapped at exposure 0, side by side: docs/images/results/gallery_<name>.jpg."""
    from PIL import Image

    from restir.image_io import linear_to_srgb, read_exr

    with open(os.path.join(report, "images.json")) as f:
        listing = json.load(f)

    def tile(method: str, kind: str):
        entry = next((e for e in listing if e["method"] == method and e["kind"] == kind), None)
        if entry is None:
            return None
        x = np.nan_to_num(read_exr(os.path.join(report, entry["file"])), nan=0.0, posinf=0.0, neginf=0.0)
        return Image.fromarray((linear_to_srgb(np.clip(x, 0.0, None)) * 255.0 + 0.5).astype(np.uint8))

    reference = tile("reference", "accumulated")
    # the compared methods (the path tracer rendered at their frame times, `pt:spp=N`, stays out)
    methods = [e["method"] for e in listing if e["kind"] == "frame" and ":" not in e["method"]]
    columns = [(reference, reference)] + [(tile(m, "frame"), tile(m, "denoised")) for m in methods]
    w, h = reference.size
    out = Image.new("RGB", (len(columns) * (w + GALLERY_GAP) - GALLERY_GAP, 2 * h + GALLERY_GAP), "white")
    for i, (top, bottom) in enumerate(columns):
        for j, img in enumerate((top, bottom)):
            if img is not None:
                out.paste(img, (i * (w + GALLERY_GAP), j * (h + GALLERY_GAP)))
    path = os.path.join("docs", "images", "results", f"gallery_{name}.jpg")
    os.makedirs(os.path.dirname(path), exist_ok=True)
    out.save(path, quality=88)
    return {"file": path, "columns": ["reference", *methods]}


def many_light_comparison(args, size, part: str, hide_emitters: bool) -> dict:
    """ReSTIR DI with and without reuse against the path tracer on builtin:<part>."""
    import restir
    from restir.compare import compare

    n = size["many_lights_size"]
    scene = restir.load_scene(f"builtin:{part}")
    scene.hide_emitters = hide_emitters
    log(f"{part}: ReSTIR DI with and without reuse against the path tracer, {n}x{n}, {size['seconds']:g} s a method")
    r = compare(scene, MANY_LIGHTS_METHODS, equal_time=size["seconds"], width=n, height=n,
                reference_spp=size["reference_spp"], warmup=size["warmup"], seed=0, denoise=True,
                correlation_runs=0)
    if r.interrupted:
        raise KeyboardInterrupt
    return {"scene": f"builtin:{part}", "hide_emitters": hide_emitters, "command": suite_command(args, [part]),
            "seconds": size["seconds"], "no_reuse": NO_REUSE, **summarize_comparison(clean(r.to_dict()))}


def part_many_lights(args, size) -> dict:
    return many_light_comparison(args, size, "many-lights", hide_emitters=True)


def part_many_delta_lights(args, size) -> dict:
    return many_light_comparison(args, size, "many-delta-lights", hide_emitters=False)


# ------------------------------------------------------------------ (d) Mitsuba 3
def part_mitsuba(args, size) -> dict:
    path = shared_scene("cornell-box")
    n = size["mitsuba_size"]
    json_out = os.path.join(LOGS, "pt_vs_mitsuba.json")
    words = [PYTHON, "benchmarks/bench_pt_vs_mitsuba.py", shown_path(path) if path else "../shared/scenes/cornell-box/scene.xml",
             "--width", str(n), "--height", str(n), "--max-depth", "8", "--spp", str(size["mitsuba_spp"]),
             "--rounds", str(size["mitsuba_rounds"]), "--json", json_out]
    out = {"command": shlex.join(words), "scene": words[2], "width": n, "height": n, "max_depth": 8,
           "spp": size["mitsuba_spp"]}
    if importlib.util.find_spec("mitsuba") is None:
        log("mitsuba: not installed")
        return {**out, "status": "not installed"}
    if path is None:
        return {**out, "status": "skipped: the shared scene cornell-box is not there"}
    log(f"mitsuba: {out['command']}")
    os.makedirs(LOGS, exist_ok=True)
    p = subprocess.run([sys.executable, *words[1:]], cwd=ROOT, capture_output=True, text=True)
    if p.returncode in (130, -2):
        raise KeyboardInterrupt
    if p.returncode != 0:
        return {**out, "status": f"failed (exit {p.returncode}): {p.stderr.strip().splitlines()[-1:]}"}
    with open(json_out) as f:
        d = json.load(f)
    med = d["medians"]
    return {**out, "status": "measured", "seconds_per_frame": med,
            "ratio": med["ours"] / med["mitsuba"], "ratio_rr": med["ours_rr"] / med["mitsuba"],
            "image_mean": {"mitsuba": d.get("mitsuba_mean"), "ours": d.get("ours_mean")}}


# ------------------------------------------------------------------ (e) scene loads
def part_loads(args, size) -> dict:
    import restir
    from restir.config import RenderConfig
    from restir.scene.builtin import BUILTINS
    from restir.scene.upload import DeviceScene

    specs = [f"builtin:{name}" for name in BUILTINS]
    root = scenes_dir()
    if root:
        specs += [os.path.join(root, d, "scene.xml") for d in sorted(os.listdir(root))
                  if os.path.isfile(os.path.join(root, d, "scene.xml"))]
    cfg = RenderConfig()
    rows = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        restir.load_scene("builtin:cornell-box")  # the loaders' imports, once
        for spec in specs:
            loads, uploads = [], []
            for _ in range(size["load_repeats"]):
                t = time.perf_counter()
                scene = restir.load_scene(spec)
                loads.append(time.perf_counter() - t)
                t = time.perf_counter()
                DeviceScene(scene, cfg.device, cfg.tracer, cfg.jitter)
                uploads.append(time.perf_counter() - t)
            name = spec if spec.startswith("builtin:") else shown_path(spec)
            rows.append({"scene": name, "triangles": scene.num_triangles,
                         "emissive_triangles": int((scene.light_power() > 0).sum()),
                         "load_s": statistics.median(loads), "upload_s": statistics.median(uploads)})
            log(f"loads: {name}: load {rows[-1]['load_s']:.2f} s, upload {rows[-1]['upload_s']:.2f} s")
    return {"command": suite_command(args, ["loads"]), "repeats": size["load_repeats"], "device": cfg.device,
            "shared_scenes": "found" if root else "not found (RESTIR_SCENES or ../shared/scenes)", "scenes": rows}


# ------------------------------------------------------------------ (f) the viewer's frame rate
def part_view(args, size) -> dict:
    spec = importlib.util.spec_from_file_location("bench_view", os.path.join(ROOT, "benchmarks", "bench_view.py"))
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    out = bench.measure("builtin:cornell-box", "restir-pt", size["view_size"], size["view_seconds"])
    log(f"view: still {out['still']['fps']:.1f} frames/s at {out['still']['width']}, moving "
        f"{out['moving']['fps']:.1f} at {out['moving']['width']}")
    return {**out, "command": f"{PYTHON} benchmarks/bench_view.py --size {size['view_size']} "
                              f"--seconds {size['view_seconds']:g}"}


# ------------------------------------------------------------------ (g) the matrix verdicts
def matrix_size(path: str) -> int | None:
    """How many cells the slow tier's matrix file has (pytest's collection), so that the page can
    say how many of them a recording covers."""
    p = subprocess.run([sys.executable, "-m", "pytest", "--collect-only", "-q", "-m", "slow", "-p", "no:xdist", path],
                       capture_output=True, text=True, cwd=ROOT)
    return sum("::" in line for line in p.stdout.splitlines()) if p.returncode == 0 else None


def part_verdicts(args, size) -> dict:
    out = {"source": VERDICTS, "how": "RESTIR_RECORD_VERDICTS=benchmarks/results/verdicts.json "
           ".venv/bin/pytest -q -m slow tests/integration/test_restir_di_matrix.py "
           "tests/integration/test_restir_pt_matrix.py tests/integration/test_suffix_restir_matrix.py"}
    if not os.path.exists(VERDICTS):
        log("verdicts: not recorded")
        return {**out, "status": "not recorded"}
    with open(VERDICTS) as f:
        records = json.load(f).get("records", [])
    files = {}
    for r in records:
        files.setdefault(r.get("file", "?"), []).append(r)
    summary = []
    for path, rs in sorted(files.items()):
        mdbs = [r["mdb"] for r in rs if r.get("mdb") is not None]
        summary.append({
            "file": path, "cells": len(rs), "cells_total": matrix_size(path),
            **{v: sum(r.get("verdict") == v for r in rs) for v in ("pass", "fail", "error")},
            "recorded": [{k: r.get(k) for k in ("test", "verdict", "mdb", "bound")} for r in rs],
            "scope": sorted({r.get("scope", "?") for r in rs}), "mdb_max": max(mdbs) if mdbs else None,
            "commits": sorted({r.get("commit", "")[:10] for r in rs}), "dirty": any(r.get("dirty") for r in rs),
            "first": min(r.get("time", "") for r in rs), "last": max(r.get("time", "") for r in rs),
            "not_passed": [{k: r.get(k) for k in ("test", "verdict", "mdb", "bound", "message")}
                           for r in rs if r.get("verdict") != "pass"]})
    log(f"verdicts: {len(records)} recorded cells")
    return {**out, "status": "recorded", "files": summary}


# ------------------------------------------------------------------ the run
RUNNERS = {"cost": part_cost, "equal-time": part_equal_time, "many-lights": part_many_lights,
           "many-delta-lights": part_many_delta_lights,
           "mitsuba": part_mitsuba, "loads": part_loads, "view": part_view, "verdicts": part_verdicts}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="smaller images, fewer frames and seconds")
    ap.add_argument("--only", nargs="+", choices=PARTS, help="run these parts only (the pages are left alone)")
    ap.add_argument("--scenes", nargs="+", choices=[s[0] for s in EQUAL_TIME_SCENES],
                    help="equal-time: these scenes only")
    ap.add_argument("--out", help=f"the JSON (default: {RESULTS}; with --only, {LOGS}/<parts>.json)")
    ap.add_argument("--no-pages", action="store_true", help="do not regenerate docs/results.md and the README's table")
    args = ap.parse_args()
    os.chdir(ROOT)
    parts = list(args.only or PARTS)
    partial = bool(args.only or args.scenes)
    out_path = args.out or (os.path.join(LOGS, "-".join(parts) + ".json") if partial else RESULTS)
    mode = "quick" if args.quick else "default"
    size = SIZES[mode]
    extra = ["--scenes", *args.scenes] if args.scenes else []
    data = {"schema": 1, "mode": mode, "command": suite_command(args, args.only, extra), "sizes": size,
            "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
            "commit": commit(), "machine": machine(), "load_average_before": list(os.getloadavg())}
    log(f"{mode} suite: {', '.join(parts)} -> {out_path}")
    try:
        for part in parts:
            t = time.perf_counter()
            data[part.replace("-", "_")] = {**RUNNERS[part](args, size), "wall_s": time.perf_counter() - t}
            log(f"{part}: {time.perf_counter() - t:.0f} s")
    except KeyboardInterrupt:
        log(f"interrupted: {out_path} left as it was")
        return 130
    data["load_average_after"] = list(os.getloadavg())
    data["wall_s"] = time.perf_counter() - _T0
    os.makedirs(os.path.dirname(os.path.abspath(out_path)), exist_ok=True)
    tmp = out_path + ".tmp"
    try:
        with open(tmp, "w") as f:
            json.dump(clean(data), f, indent=1, allow_nan=False)
            f.write("\n")
        os.replace(tmp, out_path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.remove(tmp)
        raise
    log(f"wrote {out_path} ({data['wall_s']:.0f} s in all)")
    if not partial and not args.no_pages:
        from docgen.results import main as pages

        pages([])
    return 0


if __name__ == "__main__":
    sys.exit(main())
