"""The frame's cost of `emission.rays`: a method's frame with 1, 4 and 8 camera rays a sample for
the emission seen directly, and the path tracer's 1-spp frame, in alternating rounds of one run
(ratios taken within a round: these machines are noisy).

    taskset -c 0 .venv/bin/python benchmarks/bench_emission_rays.py --size 512 --method restir-pt --scene cornell-box
"""
import argparse
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))

import numpy as np  # noqa: E402

import restir  # noqa: E402
from benchmarks.bench_error_structure import load  # noqa: E402
from restir.config import RenderConfig  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--size", type=int, default=512)
    ap.add_argument("--method", default="restir-pt")
    ap.add_argument("--scene", default="cornell-box", help="a shared scene's folder or builtin:NAME")
    ap.add_argument("--frames", type=int, default=4)
    ap.add_argument("--rounds", type=int, default=3)
    args = ap.parse_args()
    scene = load(args.scene)
    configs = [("pt", "pt", {})] + [(f"rays {n}", args.method, {"emission.rays": str(n)}) for n in (1, 4, 8)]
    ms = {label: [] for label, _, _ in configs}
    for rnd in range(args.rounds):
        for label, method, settings in configs:
            r = restir.render(scene, RenderConfig(method=method, width=args.size, height=args.size, spp=1,
                                                  frames=args.frames, seed=rnd, settings=settings))
            ms[label].append(r.stats["ms_per_frame"])
    ms = {k: np.array(v) for k, v in ms.items()}
    for label in ms:
        print(f"{label:8s} ms/frame {np.round(ms[label], 1).tolist()}  / pt {np.round(ms[label] / ms['pt'], 2).tolist()}"
              f"  / rays 1 {np.round(ms[label] / ms['rays 1'], 3).tolist()}")


if __name__ == "__main__":
    main()
