"""The frame's cost of `emission.rays`: a method's frame with one camera ray a sample for the
emission seen directly, with n at every pixel, and with n only near the emitters' edges
(`emission.adaptive`, the default), and the path tracer's 1-spp frame, in alternating rounds of
one run (ratios taken within a round: these machines are noisy). Whole frames vary by up to 25%
between rounds here, so the primary-hit stage's own time and rays are printed too: they are the
robust figures.

    RESTIR_CPU_THREADS=1 taskset -c 0 .venv/bin/python benchmarks/bench_emission_rays.py --size 512 \\
        --method restir-pt --rays 4 --frames 8 --json benchmarks/results/restir_pt/emission_adaptive_512.json

With --variance: instead, the variance of the emission seen directly (max_depth 1) over independent
runs, per pixel, with the rays adaptive and at every pixel (what the adaptive choice gives up):

    .venv/bin/python benchmarks/bench_emission_rays.py --variance --scene veach-mis --size 32 --frames 32 --runs 24
"""
import argparse
import json
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))

import numpy as np  # noqa: E402

import restir  # noqa: E402
from benchmarks.bench_error_structure import load  # noqa: E402
from restir.config import RenderConfig  # noqa: E402


def variance(args, scene):
    """Per-pixel variance of the max_depth-1 image over independent runs, adaptive against every
    pixel (the same seeds), and the pixels where the adaptive choice loses most."""
    images = {}
    for adaptive in ("false", "true"):
        images[adaptive] = np.array([
            restir.render(scene, RenderConfig(method=args.method, width=args.size, height=args.size, spp=1,
                                              frames=args.frames, max_depth=1, seed=seed,
                                              settings={"emission.rays": str(args.rays),
                                                        "emission.adaptive": adaptive})).image.sum(axis=2)
            for seed in range(args.runs)])
    every, adaptive = images["false"].var(axis=0), images["true"].var(axis=0)
    print(f"summed per-pixel variance over {args.runs} runs: every pixel {every.sum():.6g}, adaptive "
          f"{adaptive.sum():.6g} (ratio {adaptive.sum() / max(every.sum(), 1e-30):.3f})")
    worst = np.argsort(-(adaptive - every).ravel())[:5]
    for i in worst:
        y, x = divmod(int(i), args.size)
        print(f"  pixel ({y}, {x}): mean {images['false'][:, y, x].mean():.4g}, variance every pixel "
              f"{every[y, x]:.4g}, adaptive {adaptive[y, x]:.4g}")
    return {"every_pixel": float(every.sum()), "adaptive": float(adaptive.sum())}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--size", type=int, default=512)
    ap.add_argument("--method", default="restir-pt")
    ap.add_argument("--rays", type=int, default=4, help="n, the emission.rays compared with one")
    ap.add_argument("--scene", default="cornell-box", help="a shared scene's folder or builtin:NAME")
    ap.add_argument("--frames", type=int, default=8, help="frames a render (the first traces n rays everywhere)")
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--json")
    ap.add_argument("--variance", action="store_true", help="the variance check instead of the timing")
    ap.add_argument("--runs", type=int, default=24, help="--variance: independent runs")
    args = ap.parse_args()
    scene = load(args.scene)
    if args.variance:
        out = variance(args, scene)
        if args.json:
            with open(args.json, "w") as f:
                json.dump({"args": vars(args), "variance": out}, f, indent=1)
        return
    n = str(args.rays)
    configs = [("pt", "pt", {}), ("rays 1", args.method, {"emission.rays": "1"}),
               (f"rays {n} everywhere", args.method, {"emission.rays": n, "emission.adaptive": "false"}),
               (f"rays {n} adaptive", args.method, {"emission.rays": n, "emission.adaptive": "true"})]
    rows = {label: {"ms_per_frame": [], "gbuffer_ms_per_frame": [], "gbuffer_rays_per_pixel": []}
            for label, _, _ in configs}
    px = args.size * args.size * args.frames
    for rnd in range(args.rounds):
        for label, method, settings in configs:
            r = restir.render(scene, RenderConfig(method=method, width=args.size, height=args.size, spp=1,
                                                  frames=args.frames, seed=rnd, settings=settings))
            row = rows[label]
            row["ms_per_frame"].append(r.stats["ms_per_frame"])
            if method != "pt":
                row["gbuffer_ms_per_frame"].append(r.stats["stages"]["gbuffer"]["total_ms"] / args.frames)
                row["gbuffer_rays_per_pixel"].append(r.stats["rays_by_stage"]["gbuffer"] / px)
    pt = np.array(rows["pt"]["ms_per_frame"])
    for label, row in rows.items():
        ms = np.array(row["ms_per_frame"])
        row["over_pt"] = (ms / pt).tolist()
        line = f"{label:18s} ms/frame {np.round(ms, 0).tolist()}  / pt {np.round(ms / pt, 2).tolist()}"
        if row["gbuffer_ms_per_frame"]:
            line += (f"  primary hits {np.round(row['gbuffer_ms_per_frame'], 0).tolist()} ms,"
                     f" {np.round(row['gbuffer_rays_per_pixel'], 3).tolist()} rays a pixel")
        print(line, flush=True)
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"args": vars(args), "rows": rows}, f, indent=1)


if __name__ == "__main__":
    main()
