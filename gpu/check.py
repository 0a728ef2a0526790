"""The GPU check: one run on a device machine that records what CUDA gives, within a time budget.

    python3 gpu/check.py --device cuda --out $OUT            (on a device machine, docs/guide/gpu.md)
    make gpu-check DEVICE=cpu QUICK=1                         (here: the same phases at toy sizes)

Phases, in order, each given what is left of the budget (default 480 s; a phase that would not
fit is skipped and says so):

- environment: the card, the driver, Warp's view of the device, the commit;
- agreement: per method, the mean images of independent runs on the device against independent
  runs on the CPU, on two small scenes, tested as `restir validate` tests (image, tile and pixel
  z per channel, family-wise false-failure rate 1e-3, with the minimum detectable bias). The
  CPU's runs come from --cpu-runs (made beforehand by `make gpu-bundle`, keyed by the source's
  hash) or are rendered here;
- timing: each method's ms per frame, per stage, and bytes per pixel at each size on each scene,
  beside the path tracer's 1-spp frame in the same run (warm-up frames excluded, the device
  synchronised around every stage, the median of the measured frames);
- view: `restir view`'s render loop without the browser (benchmarks/bench_view.py), ReSTIR PT on
  the Cornell box at 1920 x 1080 still and at the reduced size while moving, in frames per second;
- tests: pytest on the tests marked `gpu` with --device (determinism, shifts, Jacobians, MIS
  weights);
- equal-time: `restir compare` of the path tracer, ReSTIR PT and Suffix ReSTIR at equal time,
  raw and after Open Image Denoise, with the error's correlation.

Results go to OUT/gpu_check.json and OUT/gpu_check.md, rewritten after every phase so that a run
cut short keeps what it measured.
"""
import argparse
import dataclasses
import datetime
import hashlib
import json
import os
import platform
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

METHODS = ["pt", "restir-di", "restir-pt", "suffix-restir"]
AGREEMENT_SCENES = ["builtin:cornell-box-glossy", "builtin:indirect-room"]


@dataclasses.dataclass
class Sizes:
    """What each phase renders: the full check, or toy sizes (--quick)."""
    agreement_size: int = 32
    agreement_runs: int = 64
    agreement_frames: int = 32
    agreement_spp: tuple = (("pt", 32), ("restir-di", 8), ("restir-pt", 8), ("suffix-restir", 4))
    timing_sizes: tuple = ((1280, 720), (1920, 1080))
    timing_warmup: int = 3
    timing_frames: int = 8
    equal_time_size: tuple = (1920, 1080)
    equal_time_seconds: float = 10.0
    equal_time_reference_spp: int = 1024
    equal_time_correlation_runs: int = 4
    test_selection: str | None = None  # a pytest -k expression; None: every test marked gpu
    view_size: tuple = (1920, 1080)    # restir view's render loop (benchmarks/bench_view.py)
    view_seconds: float = 10.0


QUICK = Sizes(agreement_size=12, agreement_runs=4, agreement_frames=2, agreement_spp=(),
              timing_sizes=((32, 18), (48, 27)),
              timing_warmup=1, timing_frames=2, equal_time_size=(32, 18), equal_time_seconds=0.5,
              equal_time_reference_spp=16, equal_time_correlation_runs=3,
              test_selection="bitwise_repeatable and pt", view_size=(32, 18), view_seconds=0.5)


def spp_of(method: str, s: "Sizes") -> int:
    """Samples per pixel per frame in the agreement phase: more for the methods without reuse,
    whose frames are cheap and noisy, so that every test can rule out a bias of 5%."""
    return dict(s.agreement_spp).get(method, 1)


def max_depth_of(method: str) -> int:
    return 2 if method == "restir-di" else 5  # ReSTIR DI computes direct light only


def source_hash() -> str:
    """A hash of the renderer's sources: the CPU runs of a bundle are valid for this code only."""
    h = hashlib.sha256()
    for p in sorted((ROOT / "restir").rglob("*.py")):
        h.update(str(p.relative_to(ROOT)).encode())
        h.update(p.read_bytes())
    return h.hexdigest()[:16]


def commit() -> str:
    """The commit checked: RESTIR_COMMIT, git, or (on the device, which has no .git) the bundle's
    manifest."""
    if os.environ.get("RESTIR_COMMIT"):
        return os.environ["RESTIR_COMMIT"]
    try:
        return subprocess.run(["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True, text=True,
                              check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        pass
    for manifest in sorted(ROOT.glob(".gpu-bundle/*/manifest.json")):
        return json.loads(manifest.read_text()).get("commit", "unknown")
    return "unknown"


class Check:
    def __init__(self, args, sizes: Sizes):
        self.args, self.sizes = args, sizes
        self.out = Path(args.out)
        self.out.mkdir(parents=True, exist_ok=True)
        self.t0 = time.perf_counter()
        self.results = {"command": " ".join(sys.argv), "device": args.device, "quick": args.quick,
                        "budget_s": args.budget, "started": datetime.datetime.now(datetime.timezone.utc).isoformat(),
                        "phases": {}}

    # ------------------------------------------------------------------ budget
    def left(self) -> float:
        return self.args.budget - (time.perf_counter() - self.t0)

    def phase(self, name: str, fn, minimum: float) -> None:
        """Run one phase if at least `minimum` seconds are left; record its result and time."""
        if name not in self.args.phases:
            return
        if self.left() < minimum:
            self.results["phases"][name] = {"skipped": f"{self.left():.0f} s left of the budget, the phase needs "
                                                       f"about {minimum:.0f}"}
            self.write()
            return
        print(f"== {name} ({self.left():.0f} s left)", flush=True)
        t = time.perf_counter()
        try:
            result = fn()
        except Exception as e:  # a phase's failure is a result; the later phases still run
            import traceback

            result = {"error": f"{type(e).__name__}: {e}", "traceback": traceback.format_exc()[-4000:]}
        result["seconds"] = round(time.perf_counter() - t, 1)
        self.results["phases"][name] = result
        self.write()

    # ------------------------------------------------------------------ phases
    def environment(self) -> dict:
        import warp as wp

        import restir  # noqa: F401  (Warp's options first)

        wp.init()
        env = {"commit": commit(), "source_hash": source_hash(), "python": platform.python_version(),
               "numpy": np.__version__, "warp": wp.__version__, "host": platform.node(), "cpu_count": os.cpu_count()}
        if shutil.which("nvidia-smi"):
            q = subprocess.run(["nvidia-smi", "--query-gpu=name,driver_version,memory.total,clocks.max.sm",
                                "--format=csv,noheader"], capture_output=True, text=True, timeout=30)
            env["nvidia_smi"] = q.stdout.strip() or q.stderr.strip()
        d = wp.get_device(self.args.device)
        env["warp_device"] = {k: str(getattr(d, k)) for k in ("name", "alias", "arch", "sm_count", "total_memory",
                                                               "is_cuda", "is_mempool_enabled") if hasattr(d, k)}
        for k, fn in (("toolkit_version", wp.get_cuda_toolkit_version), ("driver_version", wp.get_cuda_driver_version)):
            v = fn()
            if v:
                env[f"cuda_{k}"] = ".".join(map(str, v))
        if d.is_cuda:
            try:
                env["precompiled_kernels"] = precompiled(d)
            except Exception as e:  # a diagnostic: the check goes on without it
                env["precompiled_kernels"] = f"not determined ({type(e).__name__}: {e})"
        env["oidn"] = "pyoidn importable" if _has_oidn() else "pyoidn not importable"
        return env

    def agreement(self) -> dict:
        from restir.validation.check import compare
        from restir.validation.runs import ImageBatches, Validation

        s = self.sizes
        cpu_runs = self._cpu_runs()
        rows = []
        for spec in AGREEMENT_SCENES:
            for method in METHODS:
                if self.left() < 15:
                    rows.append({"scene": spec, "method": method, "skipped": "budget"})
                    continue
                key = agreement_key(method, spec, s)
                ref_images = cpu_runs.get(key)
                ref_source = "bundle" if ref_images is not None else "rendered here"
                if ref_images is None:
                    ref_images = render_runs(method, spec, s, "cpu", seed0=900_000)
                t = time.perf_counter()
                tested = ImageBatches(list(render_runs(method, spec, s, self.args.device, seed0=1000)))
                ref = ImageBatches(list(ref_images))
                rep = compare(tested, ref.image, ref.batch_variance_of_mean, other=ref, tile=8, alpha=1e-3)
                v = Validation(rep, tested, ref)
                rows.append({"scene": spec, "method": method, "spp": spp_of(method, s),
                             "agreement": agreement(rep), "verdict": v.verdict, "reason": v.reason,
                             "image_z": [round(float(r.image_z), 2) for r in rep.reports],
                             "max_tile_z": round(float(max(np.abs(r.tile_z).max() for r in rep.reports)), 2),
                             "mdb_percent": round(100 * rep.mdb, 2), "cpu_runs": ref_source,
                             "seconds": round(time.perf_counter() - t, 1)})
                print(f"  {method} on {spec}: {rows[-1]['agreement']}; restir validate's verdict {v.verdict} (image z "
                      f"{rows[-1]['image_z']}, MDB {rows[-1]['mdb_percent']}%)", flush=True)
        return {"runs": s.agreement_runs, "frames_per_run": s.agreement_frames, "size": s.agreement_size,
                "alpha": 1e-3, "rows": rows}

    def _cpu_runs(self) -> dict:
        path = self.args.cpu_runs
        if not path or not Path(path).exists():
            return {}
        data = np.load(path, allow_pickle=False)
        if str(data["source_hash"]) != source_hash():
            print(f"  {path} was made from other sources: the CPU runs are rendered here", flush=True)
            return {}
        return {k: data[k] for k in data.files if k != "source_hash"}

    def view(self) -> dict:
        """restir view's render loop (no browser): ReSTIR PT on the Cornell box at view_size still,
        and moving at the viewer's reduced size, in frames per second."""
        import importlib.util

        spec = importlib.util.spec_from_file_location("bench_view", ROOT / "benchmarks" / "bench_view.py")
        bench = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(bench)
        w, h = self.sizes.view_size
        return bench.measure("builtin:cornell-box", "restir-pt", h, self.sizes.view_seconds, self.args.device, w)

    def timing(self) -> dict:
        import restir
        from restir.api import make_integrator, sized_scene

        s = self.sizes
        rows = []
        for name, spec in self._timing_scenes():
            if self.left() < 20:
                rows.append({"scene": name, "skipped": "budget"})
                continue
            t_load = time.perf_counter()
            scene = restir.load_scene(spec)
            load_s = round(time.perf_counter() - t_load, 2)
            for width, height in s.timing_sizes:
                pt_ms = None
                for method in METHODS:
                    if self.left() < 20:
                        rows.append({"scene": name, "size": f"{width}x{height}", "method": method,
                                     "skipped": "budget"})
                        continue
                    t = time.perf_counter()
                    cfg = restir.RenderConfig(method=method, spp=1, width=width, height=height,
                                              device=self.args.device, max_depth=max_depth_of(method)
                                              if method == "restir-di" else None)
                    integ = make_integrator(sized_scene(scene, cfg), cfg)
                    frames, stages = [], []
                    for f in range(s.timing_warmup + s.timing_frames):
                        before = dict(integ.timer.ms)
                        t_frame = time.perf_counter()
                        integ.render_frame(f)
                        wall = (time.perf_counter() - t_frame) * 1e3
                        if f == 0:
                            first_ms = wall  # the first frame loads (or compiles) the kernels
                        if f >= s.timing_warmup:
                            frames.append(wall)
                            stages.append({k: v - before.get(k, 0.0) for k, v in integ.timer.ms.items()})
                    stage_ms = {k: round(float(np.median([st.get(k, 0.0) for st in stages])), 3)
                                for k in stages[0]}
                    frame_ms = float(np.median([sum(st.values()) for st in stages]))
                    if method == "pt":
                        pt_ms = frame_ms
                    row = {"scene": name, "size": f"{width}x{height}", "method": method,
                           "ms_per_frame": round(frame_ms, 3),
                           "wall_ms_per_frame": round(float(np.median(frames)), 3),
                           "ratio_to_pt": round(frame_ms / pt_ms, 2) if pt_ms else None,
                           "bytes_per_pixel": round(integ.buffers.per_pixel(integ.num_pixels)["total"], 1),
                           "stages_ms": stage_ms, "first_frame_ms": round(first_ms, 1),
                           "max_depth": integ.settings.max_depth, "tracer": integ.dscene.tracer_used,
                           "scene_load_s": load_s,
                           "seconds": round(time.perf_counter() - t, 1)}
                    rows.append(row)
                    print(f"  {name} {width}x{height} {method}: {frame_ms:.2f} ms/frame ({row['ratio_to_pt']}x pt), "
                          f"{row['bytes_per_pixel']} B/px", flush=True)
                    del integ
        return {"warmup_frames": s.timing_warmup, "measured_frames": s.timing_frames, "rows": rows,
                "note": "ms_per_frame: the median over the measured frames of the frame's stage times, each stage "
                        "timed between device synchronisations; wall_ms_per_frame adds the copy of the frame's mean "
                        "and variance to the host"}

    def _timing_scenes(self) -> list:
        scenes = [("cornell-box", "builtin:cornell-box")]
        folder = Path(self.args.scenes) if self.args.scenes else None
        for name, sub in (("veach-ajar", "veach-ajar"), ("modern-hall", "staircase2")):
            xml = folder / sub / "scene.xml" if folder else None
            if xml is not None and xml.exists():
                scenes.append((name, str(xml)))
            else:
                print(f"  {name}: no {sub}/scene.xml under --scenes {folder}: left out", flush=True)
        return scenes

    def tests(self) -> dict:
        cmd = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-m", "gpu", "--device",
               self.args.device, str(ROOT / "tests")]
        if self.sizes.test_selection:
            cmd += ["-k", self.sizes.test_selection]
        try:
            import xdist  # noqa: F401

            workers = max(1, min(8, (os.cpu_count() or 2) // 2))
            if workers > 1:
                cmd += ["-n", str(workers), "--dist", "loadfile"]
        except ImportError:
            pass
        timeout = max(10.0, self.left() - self.args.reserve)
        env = dict(os.environ, **({"RESTIR_SCENES": self.args.scenes} if self.args.scenes else {}))
        try:
            p = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=timeout, env=env)
            output, rc = p.stdout + p.stderr, p.returncode
        except subprocess.TimeoutExpired as e:
            output = (e.stdout or b"").decode(errors="replace") if isinstance(e.stdout, bytes) else (e.stdout or "")
            rc = "timeout"
        (self.out / "pytest.log").write_text(output)
        counts = {k: int(n) for n, k in re.findall(r"(\d+) (passed|failed|errors?|skipped|deselected)", output)}
        return {"command": " ".join(cmd[1:]), "returncode": rc, "counts": counts,
                "summary": output.strip().splitlines()[-1] if output.strip() else ""}

    def equal_time(self) -> dict:
        s = self.sizes
        folder = Path(self.args.scenes) if self.args.scenes else None
        xml = folder / "veach-ajar" / "scene.xml" if folder else None
        spec = str(xml) if xml is not None and xml.exists() else "builtin:indirect-room"
        width, height = s.equal_time_size
        out_json = self.out / "equal_time.json"
        cmd = [sys.executable, "-m", "restir", "compare", spec, "--method", "pt", "--method", "restir-pt",
               "--method", "suffix-restir", "--equal-time", str(s.equal_time_seconds), "--width", str(width),
               "--height", str(height), "--reference-spp", str(s.equal_time_reference_spp), "--device",
               self.args.device, "--correlation-runs", str(s.equal_time_correlation_runs), "--json", str(out_json),
               "--quiet"]
        denoise = _has_oidn()
        if denoise:
            cmd.append("--denoise")
        timeout = max(10.0, self.left() - self.args.reserve)
        env = dict(os.environ, RESTIR_CACHE=str(self.out / "cache"))
        try:
            p = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=timeout, env=env)
            rc, tail = p.returncode, (p.stdout + p.stderr)[-3000:]
        except subprocess.TimeoutExpired:
            rc, tail = "timeout", ""
        shutil.rmtree(self.out / "cache", ignore_errors=True)  # the reference image: not worth a file slot
        result = {"command": " ".join(["restir"] + cmd[3:]), "returncode": rc, "scene": spec,
                  "denoiser": "OIDN" if denoise else "none (pyoidn not importable)"}
        if rc != 0 or not out_json.exists():
            result["output_tail"] = tail
            return result
        data = json.loads(out_json.read_text())
        result["methods"] = [{"method": m["label"], "frames": m["frames"], **{
            k: m["metrics"].get(k) for k in ("ms_per_frame", "relmse_frame", "relmse_accumulated",
                                             "relmse_denoised_frame", "flip", "flip_denoised_frame")},
            "correlation_factor_8": (m["metrics"].get("correlation_factor") or {}).get("8")}
            for m in data["methods"]]
        result["headline"] = data.get("headline")
        result["denoiser"] = next((n for n in data.get("notes", []) if n.startswith("denoised by")), result["denoiser"])
        return result

    # ------------------------------------------------------------------ output
    def write(self) -> None:
        self.results["elapsed_s"] = round(time.perf_counter() - self.t0, 1)
        (self.out / "gpu_check.json").write_text(json.dumps(self.results, indent=1, default=str))
        (self.out / "gpu_check.md").write_text(markdown(self.results))


def precompiled(device) -> dict:
    """Which shipped kernel modules the device will load from the kernel cache (made by
    `make gpu-bundle`) rather than compile: the file Warp looks for, and whether it is there."""
    import warp as wp
    from warp._src.context import get_module

    from restir.kernel_modules import KERNEL_MODULES, import_all

    import_all()
    found, missing = [], []
    for name in KERNEL_MODULES:
        m = get_module(name)
        path = Path(wp.config.kernel_cache_dir) / m.get_module_identifier() / m._get_compile_output_name(device)
        (found if path.exists() else missing).append(path.name)
    return {"cache": wp.config.kernel_cache_dir, "found": len(found), "missing": missing}


def agreement(report) -> str:
    """CUDA against the CPU: "agree" when no test (image, tile or pixel) failed and the test could
    have seen a bias of 5% (MDB); "disagree" when one failed; "too weak" when none failed but the
    MDB is larger. Where fireflies skew the pixels' run means (median |skew| > 1), restir validate
    calls its verdict inconclusive and leaves the pixel level out: the image and tile levels still
    judge, and this says so."""
    if not report.passed:
        return "disagree"
    if not report.mdb <= 0.05:
        return "too weak"
    judged = all(r.pixel_conclusive for r in report.reports)
    return "agree" if judged else "agree (image and tiles; pixels too skewed to judge)"


def agreement_key(method: str, spec: str, s: Sizes) -> str:
    return (f"{method}|{spec}|{s.agreement_size}|{s.agreement_runs}|{s.agreement_frames}|{spp_of(method, s)}|"
            f"{max_depth_of(method)}")


def render_runs(method: str, spec: str, s: Sizes, device: str, seed0: int) -> np.ndarray:
    """(runs, H, W, 3): independent runs' average images (validation/runs.py)."""
    import restir
    from restir.validation.runs import IndependentRuns

    scene = restir.load_scene(spec, width=s.agreement_size, height=s.agreement_size)
    cfg = restir.RenderConfig(method=method, spp=spp_of(method, s), frames=s.agreement_frames, device=device,
                              max_depth=max_depth_of(method))
    return IndependentRuns(scene, cfg, s.agreement_runs, seed0=seed0).batches


def save_cpu_runs(path: str, sizes: Sizes) -> None:
    """The CPU side of the agreement phase, rendered here ahead of a device run (make gpu-bundle)."""
    arrays = {"source_hash": np.array(source_hash())}
    for spec in AGREEMENT_SCENES:
        for method in METHODS:
            arrays[agreement_key(method, spec, sizes)] = render_runs(method, spec, sizes, "cpu", seed0=900_000)
            print(f"  CPU runs: {method} on {spec}", flush=True)
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(path, **arrays)


def _has_oidn() -> bool:
    try:
        import pyoidn  # noqa: F401

        return True
    except Exception:
        return False


def table(columns: list, rows: list) -> list:
    """A markdown table's lines, and a blank line after it."""
    return (["| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]
            + ["| " + " | ".join(str(c) for c in row) + " |" for row in rows] + [""])


def markdown(r: dict) -> str:
    """The results as tables, for gpu_check.md (docs/guide/gpu.md)."""
    ph = r["phases"]
    env = ph.get("environment", {})
    lines = [f"# GPU check ({'quick, ' if r['quick'] else ''}device {r['device']})", "",
             f"- started {r['started']}, {r.get('elapsed_s')} s of a {r['budget_s']:.0f} s budget",
             f"- commit {env.get('commit', '?')}, sources {env.get('source_hash', '?')}",
             f"- card: {env.get('nvidia_smi', env.get('warp_device', {}).get('name', '?'))}; "
             f"Warp {env.get('warp', '?')}, "
             f"CUDA toolkit {env.get('cuda_toolkit_version', '-')}, driver {env.get('cuda_driver_version', '-')}",
             f"- command: `{r['command']}`", ""]
    for name, p in ph.items():
        if "skipped" in p or "error" in p:
            lines += [f"## {name}", "", f"{'skipped' if 'skipped' in p else 'error'}: {p.get('skipped') or p['error']}",
                      ""]
    if "rows" in ph.get("agreement", {}):
        a = ph["agreement"]
        lines += ["## Agreement with the CPU", "",
                  f"{a['runs']} independent runs a side, {a['frames_per_run']} frames each, "
                  f"{a['size']}x{a['size']}; alpha {a['alpha']} per test; a pass needs an MDB of at most 5%.", ""]
        lines += table(["scene", "method", "spp", "CUDA and CPU", "validate's verdict", "image z (R, G, B)",
                        "max tile z", "MDB", "CPU runs"],
                       [[x["scene"], x["method"], "", f"skipped ({x['skipped']})", "", "", "", "", ""]
                        if "skipped" in x
                        else [x["scene"], x["method"], x["spp"], x["agreement"], x["verdict"],
                              ", ".join(f"{z:+.2f}" for z in x["image_z"]), x["max_tile_z"],
                              f"{x['mdb_percent']}%", x["cpu_runs"]] for x in a["rows"]])
    if "rows" in ph.get("timing", {}):
        t = ph["timing"]
        lines += ["## Frame times", "", f"Median of {t['measured_frames']} frames after {t['warmup_frames']} of "
                  "warm-up, 1 spp; ms per frame is the sum of the stages (device synchronised around each).", ""]
        lines += table(["scene", "size", "method", "ms/frame", "x path tracer", "B/px", "first frame ms"],
                       [[x["scene"], x.get("size", ""), x.get("method", ""), "skipped", "", "", ""] if "skipped" in x
                        else [x["scene"], x["size"], x["method"], f"{x['ms_per_frame']:.2f}", x["ratio_to_pt"],
                              x["bytes_per_pixel"], f"{x['first_frame_ms']:.0f}"] for x in t["rows"]])
    if "still" in ph.get("view", {}):
        v = ph["view"]
        lines += ["## restir view", "", f"{v['method']} on `{v['scene']}`: the render loop without the browser "
                  "(benchmarks/bench_view.py).", ""]
        lines += table(["camera", "film", "frames/s", "render ms", "encode ms"],
                       [[m, f"{v[m]['width']}x{v[m]['height']}", f"{v[m]['fps']:.1f}", f"{v[m]['render_ms_median']:.1f}",
                         f"{v[m]['encode_ms_median']:.1f}"] for m in ("still", "moving")])
        lines.append("")
    if "counts" in ph.get("tests", {}):
        t = ph["tests"]
        lines += ["## Tests marked gpu", "", f"`{t['command']}`: {t['summary']} (exit {t['returncode']})", ""]
    e = ph.get("equal_time", {})
    if "methods" in e:
        def f(v):
            return "-" if v is None else f"{v:.4g}"

        lines += ["## Equal time", "", f"`{e['command']}`; denoiser: {e['denoiser']}", ""]
        lines += table(["method", "frames", "ms/frame", "relMSE per frame", "accumulated", "denoised per frame",
                        "F(8)"],
                       [[m["method"], m["frames"], f(m["ms_per_frame"]), f(m["relmse_frame"]),
                         f(m["relmse_accumulated"]), f(m["relmse_denoised_frame"]), f(m["correlation_factor_8"])]
                        for m in e["methods"]])
    elif e and "returncode" in e:
        lines += ["## Equal time", "", f"`{e['command']}` exited {e['returncode']}", ""]
    return "\n".join(lines)


PHASES = ["environment", "agreement", "timing", "view", "tests", "equal_time"]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--device", default="cuda", help="the device checked (cuda, or cpu to rehearse)")
    ap.add_argument("--budget", type=float, default=480.0, help="seconds for the whole check")
    ap.add_argument("--reserve", type=float, default=20.0, help="seconds a subprocess phase leaves to the rest")
    ap.add_argument("--out", default=os.environ.get("OUT") or "out/gpu-check", help="folder for the results")
    ap.add_argument("--quick", action="store_true", help="toy sizes (the fast tier's rehearsal)")
    ap.add_argument("--scenes", help="folder with veach-ajar/ and staircase2/ (default: ../shared/scenes or the "
                                     "bundle's)")
    ap.add_argument("--cpu-runs", help="the CPU runs of the agreement phase (.npz from --save-cpu-runs)")
    ap.add_argument("--save-cpu-runs", metavar="FILE", help="render the agreement phase's CPU runs into FILE and stop")
    ap.add_argument("--phases", default=",".join(PHASES), help="comma-separated subset of " + ", ".join(PHASES))
    args = ap.parse_args(argv)
    args.phases = [p.strip().replace("-", "_") for p in args.phases.split(",") if p.strip()]
    unknown = sorted(set(args.phases) - set(PHASES))
    if unknown:
        ap.error(f"unknown phase(s) {', '.join(unknown)}")
    sizes = QUICK if args.quick else Sizes()
    if args.save_cpu_runs:
        save_cpu_runs(args.save_cpu_runs, sizes)
        return 0
    if args.scenes is None:
        named = [Path(os.environ["RESTIR_SCENES"])] if os.environ.get("RESTIR_SCENES") else []
        for candidate in (*named, ROOT.parent / "shared" / "scenes", ROOT / ".gpu-bundle" / "scenes" / "scenes"):
            if candidate.exists():
                args.scenes = str(candidate)
                break
    if args.cpu_runs is None:
        bundled = sorted(ROOT.glob(".gpu-bundle/*/cpu_runs*.npz"))
        args.cpu_runs = str(bundled[-1]) if bundled else None
    check = Check(args, sizes)
    check.phase("environment", check.environment, 0)
    check.phase("agreement", check.agreement, 30)
    check.phase("timing", check.timing, 30)
    check.phase("view", check.view, 30 if not args.quick else 5)
    check.phase("tests", check.tests, 60 if not args.quick else 5)
    check.phase("equal_time", check.equal_time, 60 if not args.quick else 5)
    check.write()
    print((check.out / "gpu_check.md").read_text())
    failed = [n for n, p in check.results["phases"].items() if "error" in p]
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
