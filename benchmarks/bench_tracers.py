"""Our path tracer with Warp's BVH vs Embree 4 on the CPU, same scene and run, as a ratio.

    .venv/bin/python benchmarks/bench_tracers.py ../shared/scenes/cornell-box/scene.xml \\
        --width 800 --height 800 --max-depth 8 --spp 4 --rounds 2 --repeats 2
"""
import argparse
import statistics
import time

import restir
from restir.api import make_integrator


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("scene")
    ap.add_argument("--width", type=int, default=800)
    ap.add_argument("--height", type=int, default=800)
    ap.add_argument("--max-depth", type=int, default=8)
    ap.add_argument("--spp", type=int, default=4)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--repeats", type=int, default=2)
    args = ap.parse_args()
    scene = restir.load_scene(args.scene)
    scene.camera.width, scene.camera.height = args.width, args.height
    res = {"warp": [], "embree": []}
    for _ in range(args.rounds):
        for tracer in res:
            integ = make_integrator(scene, restir.RenderConfig(spp=args.spp, max_depth=args.max_depth, tracer=tracer))
            integ.render_frame(0)  # compile and warm up
            for i in range(args.repeats):
                r0 = integ.rays
                t0 = time.perf_counter()
                integ.render_frame(i + 1)
                dt = time.perf_counter() - t0
                res[tracer].append((dt, (integ.rays - r0) / dt))
    med = {k: (statistics.median(x[0] for x in v), statistics.median(x[1] for x in v)) for k, v in res.items()}
    for k, (t, r) in med.items():
        print(f"{k:7s} {t / args.spp:.3f} s per spp, {r / 1e6:.1f} Mrays/s")
    print(f"Embree speed-up: {med['warp'][0] / med['embree'][0]:.2f}x")


if __name__ == "__main__":
    main()
