"""K independent Mitsuba 3 renders of a scene file, as EXRs for `restir validate --images`.

    DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so \\
        .venv/bin/python benchmarks/mitsuba_runs.py SCENE.xml --width 160 --height 90 --spp 64 --runs 8 \\
        --max-depth 65 --out out/mitsuba-runs
    .venv/bin/restir validate SCENE.xml --method pt --images 'out/mitsuba-runs/*.exr' \\
        --ref-runs 8 --ref-spp 64 --frames 1

Mitsuba 3's `path` integrator at the given max_depth (Russian roulette as Mitsuba's default, from
depth 5: it changes the noise, not the mean), seeds 1..K. The scene is loaded as
tests/data/make_mitsuba_references.py does: its film resized (or its resx/resy defaults set), and
options Mitsuba refuses (0.6's highQualityEdges) dropped from a copy. Writes run_00.exr, ... and
runs.json (the settings, the times).
"""
import argparse
import json
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, ".."))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("scene")
    ap.add_argument("--width", type=int, required=True)
    ap.add_argument("--height", type=int, required=True)
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--runs", type=int, default=8)
    ap.add_argument("--max-depth", type=int, default=65)
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("--out", required=True)
    args = ap.parse_args()
    import mitsuba as mi

    mi.set_variant(args.variant)
    from restir.image_io import write_exr
    from tests.data.make_mitsuba_references import load_for_mitsuba

    os.makedirs(args.out, exist_ok=True)
    t0 = time.perf_counter()
    scene, integrator = load_for_mitsuba(mi, os.path.abspath(args.scene), args.width, args.height, args.max_depth,
                                         args.spp)
    load_s = time.perf_counter() - t0
    times = []
    for k in range(args.runs):
        t0 = time.perf_counter()
        img = mi.render(scene, integrator=integrator, spp=args.spp, seed=1 + k) if integrator else \
            mi.render(scene, spp=args.spp, seed=1 + k)
        img = img.numpy()[..., :3]
        times.append(time.perf_counter() - t0)
        write_exr(os.path.join(args.out, f"run_{k:02d}.exr"), img)
        print(f"run {k}: {times[-1]:.1f} s, mean {img.mean():.5g}", flush=True)
    with open(os.path.join(args.out, "runs.json"), "w") as f:
        json.dump({**vars(args), "mitsuba": mi.__version__, "load_s": load_s, "seconds": times}, f, indent=2)


if __name__ == "__main__":
    main()
