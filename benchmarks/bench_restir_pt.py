"""ReSTIR PT: per-stage timings and frame cost against the path tracer, memory per pixel, and
relMSE at equal time against the path tracer, each phase in one run.

    .venv/bin/python benchmarks/bench_restir_pt.py --phase stages    # 512x512, shared Cornell box, veach-bidir
    .venv/bin/python benchmarks/bench_restir_pt.py --phase quality   # 128x128, indirect room, veach-bidir, glossy box
    .venv/bin/python benchmarks/bench_restir_pt.py --phase cap       # the temporal cap, indirect room, 128x128
    .venv/bin/python benchmarks/bench_restir_pt.py --phase di        # ReSTIR DI's settings inside ReSTIR PT
    .venv/bin/python benchmarks/bench_restir_pt.py --phase fused     # fused against split stages, 512x512

stages: ReSTIR PT with its defaults (hybrid shift, ReSTIR DI for direct light, temporal reuse, one
spatial round of 3 neighbours) for `--frames` frames after one warm-up frame, and the path tracer
at 1 spp for the same frames, alternating (A B A B) so that machine noise hits both; reported as
per-stage ms per frame, the ratio of the two frame times, and bytes per pixel by buffer.

quality: every method renders the same static scene for 16 warm-up frames and 16 measured ones
with the same camera-sample stream. relMSE = mean over pixels and channels of
(x - ref)^2 / (ref^2 + 0.01) against the path tracer at `--ref-spp` (another seed). Two
conventions: per frame (mean relMSE of the single frames 16..31) and accumulated (relMSE of the
average of frames 16..31; the path tracer's frames are independent, ReSTIR PT's are not). The
path tracer gets ReSTIR PT's measured frame time: its frame time is fitted as a + b spp from
runs at 2 and 8 spp, and spp = round((ms_restir_pt - a) / b); both measured times are printed.
`--settings` (JSON) renders ReSTIR PT with other settings than the defaults.

fused: the shipped pipeline (trace + initial RIS and temporal reuse in one kernel, two reservoir
buffers; the same for the ReSTIR DI component's initial, visibility and temporal stages) against
`stages.split` and `di.stages.split` (each stage its own kernel, three buffers each) and the path tracer at 1 spp, at
512x512 on the shared Cornell box and veach-bidir, each `--frames` frames after a warm-up, in
`--repeats` alternating rounds (A B C A B C); frame-time ratios per round, bytes per pixel.
`--direct pt` runs both ReSTIR PT sides with direct=pt.

di: the quality phase for a grid of ReSTIR DI settings (light candidates x spatial rounds) of the
ReSTIR DI component that gives ReSTIR PT its direct light (how its defaults were chosen).
"""
import argparse
import json
import os
import sys

import numpy as np

import restir

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))


def shared(name):
    from tests.shared_scenes import scene_path

    return str(scene_path(name))


def relmse(x, ref):
    return float(np.mean((x - ref) ** 2 / (ref ** 2 + 0.01)))


def render(scene, method, frames, seed=1, spp=1, settings=None, **kw):
    return restir.render(scene, restir.RenderConfig(method=method, spp=spp, frames=frames, seed=seed,
                                                    settings=settings or {}, **kw))


def phase_stages(args, out):
    for name in ("cornell-box", "veach-bidir"):
        scene = restir.load_scene(shared(name))
        common = dict(max_depth=args.max_depth, width=512, height=512)
        render(scene, "restir-pt", 1, **common)  # compile, warm up
        render(scene, "pt", 1, **common)
        pt_ms, pt_res = [], []
        for rep in range(2):
            a = render(scene, "restir-pt", args.frames, seed=rep, **common)
            b = render(scene, "pt", args.frames, seed=rep, **common)
            pt_res.append(a)
            pt_ms.append((a.stats["ms_per_frame"], b.stats["ms_per_frame"]))
        a = pt_res[-1]
        stages = {k: v["total_ms"] / args.frames for k, v in a.stats["stages"].items()}
        ratio = [x / y for x, y in pt_ms]
        bpp = a.stats["bytes_per_pixel"]
        print(f"\n{name} 512x512 max_depth {args.max_depth}: ReSTIR PT ms per frame by stage")
        print("  " + "  ".join(f"{k} {v:.0f}" for k, v in stages.items()))
        print(f"  frame: ReSTIR PT {pt_ms[-1][0]:.0f} ms, path tracer 1 spp {pt_ms[-1][1]:.0f} ms; ratio "
              + ", ".join(f"{r:.2f}" for r in ratio) + " (two alternating repeats)")
        print(f"  bytes per pixel: {bpp['total']:.0f} in all; " +
              ", ".join(f"{k} {v:.0f}" for k, v in bpp.items() if k != "total"))
        print(f"  shifts {json.dumps(a.stats['shifts'])}; final samples {a.stats['final_samples']}")
        out[name] = {"stages_ms": stages, "frame_ms": pt_ms, "ratio": ratio, "bytes_per_pixel": bpp,
                     "shifts": a.stats["shifts"], "final_samples": a.stats["final_samples"]}


def phase_fused(args, out):
    settings = {"direct": args.direct}
    for name in ("cornell-box", "veach-bidir"):
        scene = restir.load_scene(shared(name))
        common = dict(max_depth=args.max_depth, width=512, height=512)
        split = {**settings, "stages.split": True, **({"di.stages.split": True} if args.direct == "restir-di" else {})}
        sides = {"fused": ("restir-pt", settings), "split": ("restir-pt", split),
                 "pt": ("pt", {})}
        if args.variant:  # a third ReSTIR PT side, the fused one with these settings changed
            sides["variant"] = ("restir-pt", {**settings, **json.loads(args.variant)})
        for method, st in sides.values():
            render(scene, method, 1, settings=st, **common)  # compile, warm up
        ms = {k: [] for k in sides}
        last = {}
        for rep in range(args.repeats):
            for k, (method, st) in sides.items():
                last[k] = render(scene, method, args.frames, seed=rep, settings=st, **common)
                ms[k].append(last[k].stats["ms_per_frame"])
        ratios = {"fused/pt": [a / b for a, b in zip(ms["fused"], ms["pt"])],
                  "split/pt": [a / b for a, b in zip(ms["split"], ms["pt"])],
                  "fused/split": [a / b for a, b in zip(ms["fused"], ms["split"])]}
        restir_sides = [k for k in sides if k != "pt"]
        if "variant" in sides:
            ratios["variant/pt"] = [a / b for a, b in zip(ms["variant"], ms["pt"])]
            ratios["variant/fused"] = [a / b for a, b in zip(ms["variant"], ms["fused"])]
        stages = {k: {n: v["total_ms"] / args.frames for n, v in last[k].stats["stages"].items() if v["total_ms"]}
                  for k in restir_sides}
        bpp = {k: last[k].stats["bytes_per_pixel"] for k in restir_sides}
        print(f"\n{name} 512x512 max_depth {args.max_depth}, direct={args.direct}: ms per frame "
              + "; ".join(f"{k} " + ", ".join(f"{x:.0f}" for x in v) for k, v in ms.items()))
        for k, v in ratios.items():
            print(f"  {k}: " + ", ".join(f"{x:.3f}" for x in v))
        for k in restir_sides:
            print(f"  {k} stages: " + "  ".join(f"{n} {v:.0f}" for n, v in stages[k].items()))
            print(f"  {k} bytes per pixel {bpp[k]['total']:.0f}")
        out[f"fused-{name}-{args.direct}"] = {"frame_ms": ms, "ratios": ratios, "stages_ms": stages,
                                             "bytes_per_pixel": bpp}


QUALITY_SCENES = {"indirect-room": lambda: "builtin:indirect-room", "veach-bidir": lambda: shared("veach-bidir"),
                  "cornell-box-glossy": lambda: "builtin:cornell-box-glossy"}
WARM, MEAS = 16, 16


class EqualTime:
    """One scene at args.size: the reference (path tracer at args.ref_spp, another seed) and the
    path tracer's frame time as a + b spp (fitted at 2 and 8 spp), for equal-time comparisons."""

    def __init__(self, args, spec):
        self.scene = restir.load_scene(spec)
        self.common = dict(max_depth=args.max_depth, keep_frames=True, width=args.size, height=args.size)
        self.ref = render(self.scene, "pt", 1, seed=99, spp=args.ref_spp, **self.common).image.astype(np.float64)
        render(self.scene, "restir-pt", 1, **self.common)  # compile, warm up
        t2, t8 = (render(self.scene, "pt", 4, spp=n, seed=7, **self.common).stats["ms_per_frame"] for n in (2, 8))
        self.slope = (t8 - t2) / 6.0
        self.fixed = t2 - 2 * self.slope

    def compare(self, settings):
        """ReSTIR PT with `settings` against the path tracer at its measured frame time: relMSE
        per frame (mean over frames 16..31) and accumulated (of their average), for both."""
        a = render(self.scene, "restir-pt", WARM + MEAS, settings=settings, **self.common)
        spp = max(1, int(round((a.stats["ms_per_frame"] - self.fixed) / self.slope)))
        b = render(self.scene, "pt", WARM + MEAS, spp=spp, **self.common)
        fa, fb = (r.frame_images[WARM:].astype(np.float64) for r in (a, b))
        per = [np.mean([relmse(f, self.ref) for f in fs]) for fs in (fa, fb)]
        acc = [relmse(fa.mean(0), self.ref), relmse(fb.mean(0), self.ref)]
        return {"restir_pt_ms": a.stats["ms_per_frame"], "pt_spp": spp, "pt_ms": b.stats["ms_per_frame"],
                "relmse_frame": per, "relmse_accumulated": acc, "counters": a.stats["counters"],
                "shifts": a.stats["shifts"]}


def report(name, args, r, label=""):
    per, acc = r["relmse_frame"], r["relmse_accumulated"]
    print(f"\n{name} {args.size}x{args.size} max_depth {args.max_depth}{label}: ReSTIR PT {r['restir_pt_ms']:.0f} ms "
          f"per frame; path tracer at equal time {r['pt_spp']} spp ({r['pt_ms']:.0f} ms measured)")
    print(f"  relMSE per frame: ReSTIR PT {per[0]:.4f}, path tracer {per[1]:.4f}: {per[1] / per[0]:.2f}x lower")
    print(f"  relMSE accumulated over {MEAS} frames: ReSTIR PT {acc[0]:.4f}, path tracer {acc[1]:.4f}: "
          f"{acc[1] / acc[0]:.2f}x")


def phase_quality(args, out):
    for name, spec in QUALITY_SCENES.items():
        if name in args.scenes:
            out[name] = EqualTime(args, spec()).compare(json.loads(args.settings))
            report(name, args, out[name])


# ReSTIR DI's settings inside ReSTIR PT (light candidates, spatial rounds): its own defaults (32, 2)
# and lighter ones, each at equal time against the path tracer on every quality scene.
DI_GRID = [(32, 2), (16, 1), (8, 1), (4, 1), (8, 0)]


def phase_di(args, out):
    for name, spec in QUALITY_SCENES.items():
        if name not in args.scenes:
            continue
        et = EqualTime(args, spec())
        for cand, rounds in DI_GRID:
            r = et.compare({"direct": "restir-di", "di.candidates": cand, "di.spatial.rounds": rounds})
            report(name, args, r, f", DI {cand} candidates, {rounds} spatial rounds")
            out[f"{name} di {cand}x{rounds}"] = r


def phase_cap(args, out):
    """The temporal cap by measurement (jittered camera, as ReSTIR DI's defaults were chosen):
    per-frame relMSE over frames 16..31 for each cap, two seeds, on the indirect room."""
    scene = restir.load_scene("builtin:indirect-room")
    common = dict(max_depth=args.max_depth, keep_frames=True, width=args.size, height=args.size)
    ref = render(scene, "pt", 1, seed=99, spp=args.ref_spp, **common).image.astype(np.float64)
    rows = {}
    for cap in (1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 0.0):
        errs = []
        for seed in (1, 2):
            a = render(scene, "restir-pt", 32, seed=seed, settings={"temporal.cap": cap}, **common)
            errs.append(np.mean([relmse(f, ref) for f in a.frame_images[16:].astype(np.float64)]))
        rows[cap] = errs
        print(f"  temporal.cap {cap:5.1f} ({'no cap' if cap == 0 else 'x current M'}): per-frame relMSE "
              + ", ".join(f"{e:.4f}" for e in errs) + f"  mean {np.mean(errs):.4f}")
    out["cap"] = {str(k): v for k, v in rows.items()}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--phase", choices=["stages", "quality", "cap", "di", "fused", "all"], default="all")
    ap.add_argument("--frames", type=int, default=4)
    ap.add_argument("--max-depth", type=int, default=8)
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--ref-spp", type=int, default=2048)
    ap.add_argument("--settings", default="{}", help="ReSTIR PT settings (JSON) for the quality phase")
    ap.add_argument("--scenes", nargs="+", default=["indirect-room", "veach-bidir", "cornell-box-glossy"])
    ap.add_argument("--repeats", type=int, default=3, help="alternating rounds of the fused phase")
    ap.add_argument("--direct", default="restir-di", help="ReSTIR PT's direct setting in the fused phase")
    ap.add_argument("--variant", help="the fused phase's third ReSTIR PT side: these settings (JSON) changed")
    ap.add_argument("--json")
    args = ap.parse_args()
    out = {}
    if args.phase in ("stages", "all"):
        phase_stages(args, out)
    if args.phase in ("quality", "all"):
        phase_quality(args, out)
    if args.phase in ("cap", "all"):
        phase_cap(args, out)
    if args.phase in ("di", "all"):
        phase_di(args, out)
    if args.phase in ("fused", "all"):
        phase_fused(args, out)
    if args.json:
        with open(args.json, "w") as f:
            json.dump(out, f, indent=2)


if __name__ == "__main__":
    main()
