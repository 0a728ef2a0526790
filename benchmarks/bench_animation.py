"""The per-frame cost of an animated scene: the scene update (DeviceScene.set_frame) against a
path-tracer frame, and the device memory of the previous frame's copy.

`posed_ms` is what posing the whole scene on the host costs (restir.scene.animation.posed_scene),
for scale: the update itself writes only the moving objects.

The scene: a wavy terrain of `--triangles` triangles (a grid), a sphere of `--moving` triangles
that flies over it, and a rectangular light above, seen from above at `--size` x `--size`. The
update of a frame, timed in its parts (the posed geometry on the host, the device arrays and ray
tracing structures, the light tables), is compared with a 1-spp path-tracer frame of the same
scene in the same run (median over `--frames` frames after one of warm-up each). The target: at
10^6 triangles with 1% moving, the update within 10% of a path-tracer frame at 512x512.

    .venv/bin/python benchmarks/bench_animation.py --triangles 1000000 --moving 10000 --size 512 \\
        --json benchmarks/results/animation/update_cost.json
"""
import argparse
import json
import os
import statistics
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))

import numpy as np  # noqa: E402

import restir  # noqa: E402
from restir.api import make_integrator  # noqa: E402
from restir.config import RenderConfig  # noqa: E402
from restir.scene import animation as anim  # noqa: E402
from restir.scene.scene import build_scene  # noqa: E402
from restir.scene.transforms import look_at  # noqa: E402


def terrain(triangles: int) -> dict:
    n = max(2, int(np.sqrt(triangles / 2)))
    xs = np.linspace(-1.0, 1.0, n + 1)
    x, z = np.meshgrid(xs, xs)
    y = 0.03 * np.sin(9 * x) * np.cos(7 * z)
    v = np.stack([x, y, z], -1).reshape(-1, 3)
    i = np.arange(n * (n + 1)).reshape(n, n + 1)[:, :n].reshape(-1)
    f = np.concatenate([np.stack([i, i + n + 1, i + 1], 1), np.stack([i + 1, i + n + 1, i + n + 2], 1)])
    return {"type": "trimesh", "vertices": v, "faces": f,
            "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.6, 0.6, 0.6]}}}


def scene(triangles: int, moving: int, size: int):
    seg = max(4, int(np.sqrt(moving / 4)))
    return build_scene({
        "type": "scene",
        "integrator": {"type": "path", "max_depth": 5},
        "sensor": {"type": "perspective", "fov": 50, "to_world": look_at([0, 2.2, -1.6], [0, 0, 0], [0, 1, 0]),
                   "film": {"type": "hdrfilm", "width": size, "height": size}},
        "terrain": terrain(triangles),
        "ball": {"type": "sphere", "center": [0, 0.3, 0], "radius": 0.2, "segments": seg,
                 "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.7, 0.3, 0.2]}}},
        "light": {"type": "rectangle", "to_world": np.array([[0.3, 0, 0, 0], [0, 0, 0.3, 1.5], [0, -1, 0, 0],
                                                              [0, 0, 0, 1.0]]),
                  "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [20, 20, 20]}}},
    }, "bench-animation")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--triangles", type=int, default=1_000_000)
    ap.add_argument("--moving", type=int, default=10_000)
    ap.add_argument("--size", type=int, default=512)
    ap.add_argument("--frames", type=int, default=5)
    ap.add_argument("--json", help="write the measurements here")
    a = ap.parse_args()

    static = scene(a.triangles, a.moving, a.size)
    moving = anim.animate(static, {"ball": anim.Motion(translation=([0, 100], [[-0.8, 0, -0.8], [0.8, 0, 0.8]]))})
    lo, hi = moving.objects["ball"]
    print(f"{static.num_triangles} triangles, {hi - lo} moving ({100 * (hi - lo) / static.num_triangles:.2f}%), "
          f"{a.size}x{a.size}", flush=True)

    cfg = RenderConfig(method="pt", spp=1, frames=1)
    pt = make_integrator(static, cfg)
    pt.render_frame(0)
    frame_ms = []
    for f in range(1, a.frames + 1):
        t = time.perf_counter()
        pt.render_frame(f)
        frame_ms.append(1e3 * (time.perf_counter() - t))

    integ = make_integrator(moving, cfg)
    integ.render_frame(0)
    moving_frame_ms = []  # the path tracer in the animated scene (Embree's two-level structure)
    for f in range(1, a.frames + 1):
        t = time.perf_counter()
        integ.render_frame(f)
        moving_frame_ms.append(1e3 * (time.perf_counter() - t))
    d = integ.dscene
    d.set_frame(a.frames + 1)  # warm-up: both slots made
    parts = {"posed": [], "update": []}
    for f in range(a.frames + 2, 2 * a.frames + 2):
        t = time.perf_counter()
        anim.posed_scene(moving, f)
        parts["posed"].append(1e3 * (time.perf_counter() - t))
        t = time.perf_counter()
        d.set_frame(f)
        parts["update"].append(1e3 * (time.perf_counter() - t))
    update_ms = statistics.median(parts["update"])
    pt_ms = statistics.median(frame_ms)
    static_bytes = make_integrator(static, cfg).dscene.memory_bytes()
    out = {
        "command": " ".join(sys.argv), "triangles": int(static.num_triangles), "moving": int(hi - lo), "size": a.size,
        "pt_frame_ms": pt_ms, "pt_frame_ms_animated": statistics.median(moving_frame_ms), "update_ms": update_ms, "posed_ms": statistics.median(parts["posed"]),
        "update_over_frame": update_ms / pt_ms, "tracer": d.tracer_used,
        "scene_bytes_static": static_bytes, "scene_bytes_animated": d.memory_bytes(),
    }
    print(f"path-tracer frame {pt_ms:.1f} ms (in the animated scene, update included: "
          f"{out['pt_frame_ms_animated']:.1f} ms); scene update {update_ms:.1f} ms ({100 * out['update_over_frame']:.1f}% "
          f"of a frame; posing the whole scene on the host, which the update avoids, would take "
          f"{out['posed_ms']:.1f} ms); scene memory "
          f"{static_bytes / 2**20:.1f} MiB static, {out['scene_bytes_animated'] / 2**20:.1f} MiB animated")
    if a.json:
        os.makedirs(os.path.dirname(os.path.abspath(a.json)), exist_ok=True)
        with open(a.json, "w") as fh:
            json.dump(out, fh, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
