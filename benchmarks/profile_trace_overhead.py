"""What ReSTIR PT's base paths cost beyond the path tracer's, before any reuse: ReSTIR PT with
temporal and spatial reuse off (`temporal=false spatial.rounds=0`: the G-buffer, the trace with
streaming RIS over every event, the shade) against the path tracer at 1 spp, on the shared Cornell
box at 512x512, for several max_depth (a fixed cost per pixel shows as the same difference at
every depth, a per-bounce one grows with it), two alternating rounds of 3 frames.

    taskset -c 0 .venv/bin/python benchmarks/profile_trace_overhead.py [--depths 2 4 8]
"""
import argparse
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))

import restir  # noqa: E402
from tests.shared_scenes import scene_path  # noqa: E402


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--depths", type=int, nargs="+", default=[2, 4, 8])
    ap.add_argument("--size", type=int, default=512)
    args = ap.parse_args()
    scene = restir.load_scene(str(scene_path("cornell-box")))
    sides = {"pt": ("pt", {}), "trace only": ("restir-pt", {"temporal": False, "spatial.rounds": 0})}
    for depth in args.depths:
        common = dict(max_depth=depth, width=args.size, height=args.size, spp=1)
        for method, st in sides.values():  # compile, warm up
            restir.render(scene, restir.RenderConfig(method=method, frames=1, settings=st, **common))
        for rnd in range(2):
            ms, stages = {}, {}
            for name, (method, st) in sides.items():
                r = restir.render(scene, restir.RenderConfig(method=method, frames=3, seed=rnd, settings=st, **common))
                ms[name] = r.stats["ms_per_frame"]
                stages[name] = {k: round(v["total_ms"] / 3) for k, v in r.stats["stages"].items() if v["total_ms"]}
            print(f"max_depth {depth}, round {rnd}: path tracer {ms['pt']:.0f} ms, trace only {ms['trace only']:.0f} ms "
                  f"({stages['trace only']}); difference {ms['trace only'] - ms['pt']:.0f} ms, ratio "
                  f"{ms['trace only'] / ms['pt']:.3f}", flush=True)


if __name__ == "__main__":
    main()
