"""Same-run A/B of a method (the path tracer by default) between two checkouts of restir (per-frame
time ratio).

    .venv/bin/python benchmarks/bench_ab.py --a /path/to/old/checkout --b . --rounds 5

Each round renders the same frames in a fresh process for A, then for B (alternating, so machine
load drifts affect both alike); compilation and one warm-up frame are excluded. Prints the
medians and the ratio B/A.
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
t = []
for f in range(int(sys.argv[4])):
    t0 = time.perf_counter(); integ.render_frame(f + 1); t.append((time.perf_counter() - t0) * 1e3)
print(json.dumps({"file": restir.__file__, "ms": t}))
"""


def run(path, args):
    # the checkout's own package first: `python -c` puts the working folder ahead of everything
    env = dict(os.environ, PYTHONPATH=os.path.abspath(path))
    out = subprocess.run([sys.executable, "-c", CHILD, args.scene, str(args.size), str(args.spp), str(args.frames),
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
    args = ap.parse_args()
    ms = {"a": [], "b": []}
    for r in range(args.rounds):
        for side in ("a", "b"):
            res = run(getattr(args, side), args)
            ms[side] += res["ms"]
            print(f"round {r} {side} ({res['file']}): {statistics.median(res['ms']):.1f} ms/frame", flush=True)
    ma, mb = statistics.median(ms["a"]), statistics.median(ms["b"])
    print(f"median ms/frame  A {ma:.1f}  B {mb:.1f}  B/A {mb / ma:.3f}")


if __name__ == "__main__":
    main()
