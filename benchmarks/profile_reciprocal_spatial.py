"""Where ReSTIR PT's reciprocal spatial pass spends its time: the pass as shipped, the same kernel
built over a shift that fails at once (everything but the shifts' own work: the loads, the
neighbour tests, the resampling and the state kept between launches), and the independent pass,
each launched on the same inputs (the reservoirs after two frames) in alternating rounds.

    taskset -c 0 .venv/bin/python benchmarks/profile_reciprocal_spatial.py [--size 512] [--rounds 3]
"""
import argparse
import os
import sys
import time

import warp as wp

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))

import restir  # noqa: E402
from restir.api import make_integrator, sized_scene  # noqa: E402
from restir.device.scene_device import SceneDevice  # noqa: E402
from restir.integrators.common.events import EventCounts, PassCounts  # noqa: E402
from restir.integrators.path_reuse.domain import Domain  # noqa: E402
from restir.integrators.path_reuse.path_sample import PathReservoir  # noqa: E402
from restir.integrators.path_reuse.shift import ShiftResult  # noqa: E402
from restir.integrators.restir_pt.s4_spatial import (make_reciprocal_spatial_kernel, pairings_kernel,  # noqa: E402
                                                     reciprocal_spatial_kernel, spatial_kernel)
from tests.shared_scenes import scene_path  # noqa: E402


@wp.func
def failed_shift(scene: SceneDevice, r: PathReservoir, dst: Domain) -> ShiftResult:
    return ShiftResult()  # valid = 0: what a shift costs besides its own work


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--size", type=int, default=512)
    ap.add_argument("--rounds", type=int, default=3)
    args = ap.parse_args()
    no_shift_kernel = make_reciprocal_spatial_kernel(shift=failed_shift, module="profile_failed_shift")
    cfg = restir.RenderConfig(method="restir-pt", spp=1, max_depth=8, seed=1, width=args.size, height=args.size)
    integ = make_integrator(sized_scene(restir.load_scene(str(scene_path("cornell-box"))), cfg), cfg)
    integ.render_frame(0)
    integ.render_frame(1)
    n, k = integ.num_pixels, integ.settings.spatial.neighbors
    p = integ.params(2, 0)
    p.spatial_round = 0
    wp.launch(pairings_kernel, dim=k, inputs=[p], outputs=[integ.pairings], device=integ.device)
    sc, gb, cur = integ.dscene.scene, integ.gbuffers.current, integ.reservoirs.current
    out = wp.empty_like(cur)
    sums = wp.zeros(n, dtype=wp.vec3, device=integ.device)
    shifts = wp.zeros(n, dtype=PassCounts, device=integ.device)
    events = wp.zeros(n, dtype=EventCounts, device=integ.device)

    def reciprocal(kernel):
        for j in range(k):
            wp.launch(kernel, dim=n, inputs=[0, j, sc, p, integ.width, integ.height, gb, integ.pairings, cur],
                      outputs=[out, sums, shifts, events], device=integ.device)

    sides = {"reciprocal (shipped)": lambda: reciprocal(reciprocal_spatial_kernel),
             "reciprocal, every shift failing at once": lambda: reciprocal(no_shift_kernel),
             "independent": lambda: wp.launch(spatial_kernel, dim=n, inputs=[0, sc, p, integ.width, integ.height, gb,
                                                                              cur],
                                              outputs=[out, shifts, events], device=integ.device)}
    for run in sides.values():
        run()  # compile, warm up
    wp.synchronize()
    ms = {name: [] for name in sides}
    for _ in range(args.rounds):
        for name, run in sides.items():
            t = time.perf_counter()
            run()
            wp.synchronize()
            ms[name].append(1e3 * (time.perf_counter() - t))
    print(f"cornell-box {args.size}x{args.size}, k = {k}, one launch thread (ms per pass, {args.rounds} rounds):")
    for name, v in ms.items():
        print(f"  {name:42s} " + " ".join(f"{x:.0f}" for x in v))


if __name__ == "__main__":
    main()
