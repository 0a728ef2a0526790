"""What a denoiser sees, on every scene the project has: `restir compare` at equal time with
`--denoise` and the error-structure metrics, one table (docs/guide/when_restir_pays.md shows them).

    .venv/bin/python benchmarks/bench_error_structure.py --seconds 4 --lines 128 --out out/bench_error_structure.json

Per scene: the path tracer, ReSTIR PT and Suffix ReSTIR at the scene's depth, and (on the two
scenes with direct light worth resampling) the path tracer and ReSTIR DI at max_depth 2, ReSTIR
DI's only depth. Each comparison also renders the path tracer at every other method's frame
time (the fair per-frame baseline; its spp fitted as a + b spp, its error interpolated between
the whole spp on both sides) and 8 independent runs per method for the radial correlation.
Scenes are rendered at `--lines` lines at their own aspect. The reference is the path tracer at
`--ref-spp` (cached); its own relMSE is printed, since every denoised error includes it.
`--frames F` compares at equal samples instead (F frames of 1 spp per method, `--warmup` of them
before the per-frame error is measured); `--runs 0` skips the radial correlation (F(8) and the
temporal correlation come from the measured frames anyway).
"""
import argparse
import json
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))

import restir  # noqa: E402
from restir.compare import compare  # noqa: E402
from restir.compare.headline import factor_text  # noqa: E402

FULL = ["pt", "restir-pt", "suffix-restir"]
DIRECT = ["pt", "restir-di"]
SCENES = [  # (name, scene, aspect width/height, methods, max_depth)
    ("indirect-room", "builtin:indirect-room", 1.0, FULL, None),
    ("cornell-box-glossy", "builtin:cornell-box-glossy", 1.0, FULL, None),
    ("cornell-box (shared)", "cornell-box", 1.0, FULL, None),
    ("veach-bidir", "veach-bidir", 1.0, FULL, None),
    ("veach-mis", "veach-mis", 16 / 9, FULL, None),
    ("veach-mis, depth 2", "veach-mis", 16 / 9, DIRECT, 2),
    ("cornell-box (shared), depth 2", "cornell-box", 1.0, DIRECT, 2),
    ("veach-ajar", "veach-ajar", 16 / 9, FULL, None),
    ("staircase2", "staircase2", 16 / 9, FULL, None),
]


def load(spec):
    if spec.startswith("builtin:"):
        return restir.load_scene(spec)
    root = os.environ.get("RESTIR_SCENES") or os.path.join(os.path.dirname(__file__), "..", "..", "shared", "scenes")
    return restir.load_scene(os.path.normpath(os.path.join(root, spec, "scene.xml")))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--seconds", type=float, default=4.0, help="equal-time budget per method")
    ap.add_argument("--frames", type=int, help="equal samples instead: this many frames per method (warm-up "
                    "included), the same spp")
    ap.add_argument("--warmup", type=int, default=4, help="frames before the per-frame error is measured")
    ap.add_argument("--lines", type=int, default=128, help="image height")
    ap.add_argument("--ref-spp", type=int, default=1024)
    ap.add_argument("--runs", type=int, default=8, help="independent runs for the radial correlation")
    ap.add_argument("--seed", type=int, default=0, help="the methods' seed (the reference's is fixed)")
    ap.add_argument("--only", nargs="*", help="scene names to run (default: all)")
    ap.add_argument("--methods", nargs="*", help="methods to compare on every scene, 'name:key=value,...' "
                    "(default: the scene's own list)")
    ap.add_argument("--out", default="out/bench_error_structure.json")
    ap.add_argument("--no-jitter", dest="jitter", action="store_false",
                    help="pixel-centre primary rays for every method and the reference (RenderConfig.jitter): no "
                    "anti-aliasing noise, each pixel one primary hit")
    ap.add_argument("--report", metavar="DIR", help="also write each scene's HTML report into DIR/<scene>")
    args = ap.parse_args()
    rows = []
    for name, spec, aspect, methods, depth in SCENES:
        if args.only and name not in args.only:
            continue
        h = args.lines
        w = int(round(h * aspect / 2)) * 2
        budget = dict(frames=args.frames) if args.frames else dict(equal_time=args.seconds)
        r = compare(load(spec), args.methods or methods, **budget, warmup=args.warmup, width=w, height=h,
                    max_depth=depth, reference_spp=args.ref_spp, denoise=True, correlation_runs=args.runs,
                    seed=args.seed, jitter=args.jitter)
        heads = {x["method"]: x for x in r.headline}
        if args.report:
            from restir.compare.report import write_report

            write_report(r, os.path.join(args.report, name.replace(" ", "_").replace(",", "")))
        print(f"\n## {name} ({w}x{h}; reference's own relMSE {r.reference.own_relmse():.3g})")
        for note in r.notes:
            print("note:", note)
        for m in r.methods:
            x = m.metrics
            radial = dict(zip(m.radial["radii"], m.radial["values"])) if m.radial else {r_: None for r_ in (1, 4, 8, 16)}
            hd = heads.get(m.label, {})
            row = {"scene": name, "size": f"{w}x{h}", "method": m.label, "ms_per_frame": x["ms_per_frame"],
                   "frames": m.frames, "relmse_frame": x["relmse_frame"],
                   "relmse_denoised_frame": x["relmse_denoised_frame"], "relmse_accumulated": x["relmse_accumulated"],
                   "factor_raw": hd.get("raw_frame"), "factor_denoised": hd.get("denoised_frame"),
                   "baseline": hd.get("baseline"), "baseline_spp": hd.get("baseline_spp"),
                   "correlation_factor_8": x["correlation_factor"]["8"],
                   "radial": {r_: radial[r_] for r_ in (1, 4, 8, 16)}, "temporal": x["temporal_correlation"],
                   "reference_relmse": r.reference.own_relmse()}
            rows.append(row)
            print(f"| {name} | {m.label} | {x['ms_per_frame']:.1f} | {x['relmse_frame']:.3g} | "
                  f"{x['relmse_denoised_frame']:.3g} | {factor_text(hd.get('raw_frame')) if hd else ''} | "
                  f"{factor_text(hd.get('denoised_frame')) if hd else ''} | {x['correlation_factor']['8']:.2f} | "
                  + " | ".join("n/a" if radial[r_] is None else f"{radial[r_]:.3f}" for r_ in (1, 4, 8, 16))
                  + " | " + ("n/a" if x["temporal_correlation"] is None else f"{x['temporal_correlation']:.3f}")
                  + f" | {x['relmse_accumulated']:.3g} |", flush=True)  # n/a: fewer than two measured frames
        os.makedirs(os.path.dirname(args.out) or ".", exist_ok=True)
        with open(args.out, "w") as f:
            json.dump({"args": vars(args), "rows": rows}, f, indent=2)


if __name__ == "__main__":
    main()
