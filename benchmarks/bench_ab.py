"""Same-run A/B of a method (the path tracer by default) between two checkouts of restir (per-frame
time ratio).

    .venv/bin/python benchmarks/bench_ab.py --a /path/to/old/checkout --b . --rounds 5

Each round renders the same frames in a fresh process for A, then for B (alternating, so machine
load drifts affect both alike); compilation and one warm-up frame are excluded. Prints the
medians, the ratio B/A of the medians, the median of the rounds' ratios and the ratio of the
fastest frames (noise only adds time, so on a busy machine the minimum is the steadier one).
`--pin CORE` runs every process on that core (taskset), so the two sides never share it with
their own threads. `--stages` also prints each stage's ms per call on both sides (the median over
rounds and the ratio): a slowdown confined to a few stages points at the code they share.
"""
import argparse
import json
import os
import statistics
import subprocess
import sys

CHILD = r"""
import json, sys, time
import restir
from restir.config import RenderConfig
from restir.api import make_integrator, _init_warp
_init_warp()
scene = restir.load_scene(sys.argv[1])
scene.camera.width = scene.camera.height = int(sys.argv[2])
integ = make_integrator(scene, RenderConfig(method=sys.argv[6], spp=int(sys.argv[3]), settings=json.loads(sys.argv[5])))
integ.render_frame(0)
integ.timer.ms.clear(); integ.timer.calls.clear()  # the warm-up frame's stages are not counted
t = []
for f in range(int(sys.argv[4])):
    t0 = time.perf_counter(); integ.render_frame(f + 1); t.append((time.perf_counter() - t0) * 1e3)
stages = {k: v["ms_per_call"] for k, v in integ.timer.summary().items()}
print(json.dumps({"file": restir.__file__, "ms": t, "stages": stages}))
"""


def run(path, args):
    # the checkout's own package first: `python -c` puts the working folder ahead of everything
    env = dict(os.environ, PYTHONPATH=os.path.abspath(path))
    pin = ["taskset", "-c", str(args.pin)] if args.pin is not None else []
    out = subprocess.run(pin + [sys.executable, "-c", CHILD, args.scene, str(args.size), str(args.spp), str(args.frames),
                          args.settings, args.method], env=env, cwd=os.path.abspath(path), capture_output=True, text=True,
                         check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--a", required=True)
    ap.add_argument("--b", required=True)
    ap.add_argument("--scene", default="builtin:cornell-box")
    ap.add_argument("--size", type=int, default=192)
    ap.add_argument("--spp", type=int, default=8)
    ap.add_argument("--frames", type=int, default=3)
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--settings", default="{}", help="method settings as JSON")
    ap.add_argument("--method", default="pt")
    ap.add_argument("--pin", type=int, default=None, help="run every process on this CPU core (taskset)")
    ap.add_argument("--warmup", action="store_true", help="one untimed round first (fills both kernel caches)")
    ap.add_argument("--stages", action="store_true", help="also print each stage's ms per call, A and B")
    args = ap.parse_args()
    if args.warmup:
        for side in ("a", "b"):
            run(getattr(args, side), args)
    ms = {"a": [], "b": []}
    stages = {"a": [], "b": []}
    ratios = []
    for r in range(args.rounds):
        med = {}
        for side in ("a", "b") if r % 2 == 0 else ("b", "a"):
            res = run(getattr(args, side), args)
            ms[side] += res["ms"]
            stages[side].append(res.get("stages", {}))
            med[side] = statistics.median(res["ms"])
            print(f"round {r} {side} ({res['file']}): {med[side]:.1f} ms/frame", flush=True)
        ratios.append(med["b"] / med["a"])
    ma, mb = statistics.median(ms["a"]), statistics.median(ms["b"])
    print(f"median ms/frame  A {ma:.1f}  B {mb:.1f}  B/A {mb / ma:.3f}; median of round ratios "
          f"{statistics.median(ratios):.3f} (rounds {min(ratios):.3f}-{max(ratios):.3f}); fastest frames "
          f"A {min(ms['a']):.1f} B {min(ms['b']):.1f} B/A {min(ms['b']) / min(ms['a']):.3f}")
    if args.stages:
        print("stage: median ms per call A, B, B/A")
        for name in stages["b"][0]:
            if name not in stages["a"][0]:
                print(f"  {name:16s} only in B")
                continue
            a = statistics.median(r[name] for r in stages["a"])
            b = statistics.median(r[name] for r in stages["b"])
            print(f"  {name:16s} {a:9.2f} {b:9.2f} {b / a if a else float('nan'):7.3f}")


if __name__ == "__main__":
    main()
