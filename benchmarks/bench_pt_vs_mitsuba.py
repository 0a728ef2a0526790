"""Path tracer vs Mitsuba 3 (`llvm_ad_rgb`, `path`) on one scene, in one run, as a ratio.

    DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so \\
    .venv/bin/python benchmarks/bench_pt_vs_mitsuba.py ../shared/scenes/cornell-box/scene.xml \\
        --width 800 --height 800 --max-depth 8 --spp 4 --rounds 3

Both renderers get the same scene file, resolution, max_depth and spp, and all cores. Mitsuba
runs in a worker process (its LLVM and Warp's compiler are kept apart); each renderer compiles
and warms up first, then the two alternate in `rounds` blocks of `repeats` timed renders, and
the reported ratio is of the medians (these machines are noisy). Mitsuba's `path` uses Russian
roulette from depth 5 by default, so ours is timed with RR off (our default) and with RR on
(the same rule); the Mitsuba timing includes its film development (a synchronous numpy copy).
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import time

WORKER = r"""
import json, sys, time
import drjit as dr, mitsuba as mi
mi.set_variant("llvm_ad_rgb")
a = json.loads(sys.argv[1])
scene = mi.load_file(a["scene"], resx=a["width"], resy=a["height"], max_depth=a["max_depth"], spp=a["spp"])
mi.render(scene, spp=a["spp"], seed=0).numpy()  # JIT compile + warm up
times = []
for i in range(a["repeats"]):
    t0 = time.perf_counter()
    img = mi.render(scene, spp=a["spp"], seed=1 + i).numpy()
    times.append(time.perf_counter() - t0)
print(json.dumps({"times": times, "mean": float(img[..., :3].mean())}))
"""


def mitsuba_block(args):
    env = dict(os.environ)
    env.setdefault("DRJIT_LIBLLVM_PATH", "/usr/lib/x86_64-linux-gnu/libLLVM-19.so")
    payload = json.dumps({"scene": os.path.abspath(args.scene), "width": args.width, "height": args.height,
                          "max_depth": args.max_depth, "spp": args.spp, "repeats": args.repeats})
    out = subprocess.run([sys.executable, "-c", WORKER, payload], capture_output=True, text=True, env=env)
    if out.returncode != 0:
        raise SystemExit(f"Mitsuba worker failed:\n{out.stderr}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def ours_block(args, rr: bool):
    import restir
    from restir.api import make_integrator

    scene = restir.load_scene(args.scene)
    scene.camera.width, scene.camera.height = args.width, args.height
    cfg = restir.RenderConfig(spp=args.spp, max_depth=args.max_depth, settings={"rr": rr})
    integ = make_integrator(scene, cfg)   # compiles the kernels
    integ.render_frame(0)                 # warm up
    times, rays, mean = [], 0, 0.0
    for i in range(args.repeats):
        r0 = integ.rays
        t0 = time.perf_counter()
        img, _ = integ.render_frame(1 + i)
        times.append(time.perf_counter() - t0)
        rays += integ.rays - r0
        mean = float(img.mean())
    return {"times": times, "rays_per_s": rays / sum(times), "mean": mean}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scene")
    ap.add_argument("--width", type=int, default=800)
    ap.add_argument("--height", type=int, default=800)
    ap.add_argument("--max-depth", type=int, default=8)
    ap.add_argument("--spp", type=int, default=4)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--json", help="write the raw timings here")
    args = ap.parse_args()
    res = {"mitsuba": [], "ours": [], "ours_rr": []}
    info = {}
    for _ in range(args.rounds):
        m = mitsuba_block(args)
        res["mitsuba"] += m["times"]
        info["mitsuba_mean"] = m["mean"]
        o = ours_block(args, rr=False)
        res["ours"] += o["times"]
        info["ours_rays_per_s"] = o["rays_per_s"]
        info["ours_mean"] = o["mean"]
        o = ours_block(args, rr=True)
        res["ours_rr"] += o["times"]
        info["ours_rr_rays_per_s"] = o["rays_per_s"]
    med = {k: statistics.median(v) for k, v in res.items()}
    per_spp = {k: v / args.spp for k, v in med.items()}
    print(f"scene {args.scene}  {args.width}x{args.height}  max_depth {args.max_depth}  spp {args.spp}  "
          f"({args.rounds} rounds x {args.repeats} renders each, medians)")
    print(f"  Mitsuba 3 llvm_ad_rgb path (RR from depth 5): {per_spp['mitsuba']:.3f} s per spp")
    print(f"  restir pt, RR off:  {per_spp['ours']:.3f} s per spp  ratio {med['ours'] / med['mitsuba']:.2f}x  "
          f"{info['ours_rays_per_s'] / 1e6:.1f} Mrays/s")
    print(f"  restir pt, RR on:   {per_spp['ours_rr']:.3f} s per spp  ratio {med['ours_rr'] / med['mitsuba']:.2f}x  "
          f"{info['ours_rr_rays_per_s'] / 1e6:.1f} Mrays/s")
    print(f"  image means (sanity): Mitsuba {info['mitsuba_mean']:.4f}, restir {info['ours_mean']:.4f}")
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"args": vars(args), "times": res, "medians": med, **info}, f, indent=2)


if __name__ == "__main__":
    main()
