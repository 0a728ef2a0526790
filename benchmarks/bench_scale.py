"""Loading a large scene: restir against Mitsuba 3 on the same file.

    DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so \\
        .venv/bin/python benchmarks/bench_scale.py SCENE.xml [--repeats 3] [--out out/bench_scale.json]

Each side runs in a fresh process per repeat (so the memory it reports is that scene's alone, on
top of the interpreter and the imported libraries), warm file cache. restir: the host load
(`load_scene`: XML, meshes, materials, textures), then the device scene (`DeviceScene`: Warp's
BVH and Embree's), Embree's build and Warp's BVH build timed again on their own, the host mesh
arrays' bytes per triangle, the textures' bytes, the device arrays' bytes per triangle (textures
included), the process's resident-memory growth, and each method's render buffers in bytes per
pixel (`stats['bytes_per_pixel']`, from a 64x36 frame). Mitsuba 3: `mi.load_file` (which builds
its Embree scene; the time Embree took is read from Mitsuba's own log line) and the process's
resident-memory growth. Options Mitsuba refuses (0.6's highQualityEdges) are dropped from its
copy, as tests/data/make_mitsuba_references.py does.
"""
import argparse
import json
import os
import re
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, ".."))

METHODS = ("pt", "restir-di", "restir-pt", "suffix-restir")


def rss_bytes() -> int:
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) * 1024
    raise RuntimeError("no VmRSS in /proc/self/status")


def restir_side(path: str) -> dict:
    import numpy as np
    import warp as wp

    import restir
    from restir.embree import EmbreeScene
    from restir.scene.upload import DeviceScene

    wp.init()
    rss0 = rss_bytes()
    t0 = time.perf_counter()
    scene = restir.load_scene(path)
    load_s = time.perf_counter() - t0
    rss_host = rss_bytes()
    tris = scene.num_triangles
    host_bytes = sum(v.nbytes for v in vars(scene).values() if isinstance(v, np.ndarray))
    texture_bytes = sum(t.image.nbytes for t in scene.textures if t.image is not None)
    t0 = time.perf_counter()
    dev = DeviceScene(scene, "cpu")
    device_s = time.perf_counter() - t0
    rss_dev = rss_bytes()
    # Embree's build on its own (DeviceScene builds Warp's BVH, then Embree's): the same call again
    t0 = time.perf_counter()
    EmbreeScene(scene.positions)
    embree_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    pts = wp.array(scene.positions.reshape(-1, 3).astype(np.float32), dtype=wp.vec3)
    wp.Mesh(points=pts, indices=wp.array(np.arange(len(pts), dtype=np.int32), dtype=wp.int32))
    warp_bvh_s = time.perf_counter() - t0
    per_pixel = {}
    for m in METHODS:
        r = restir.render(scene, method=m, width=64, height=36, spp=1, frames=1, max_depth=2 if m == "restir-di" else None)
        per_pixel[m] = r.stats["bytes_per_pixel"]["total"]
    return {"triangles": tris, "load_s": load_s, "device_scene_s": device_s, "embree_build_s": embree_s,
            "warp_bvh_s": warp_bvh_s, "host_mesh_bytes_per_triangle": host_bytes / tris,
            "host_texture_mb": texture_bytes / 2**20, "device_bytes_per_triangle": dev.memory_bytes() / tris,
            "rss_growth_host_bytes_per_triangle": (rss_host - rss0) / tris,
            "rss_growth_bytes_per_triangle": (rss_dev - rss0) / tris, "render_bytes_per_pixel": per_pixel}


def mitsuba_side(path: str, variant: str) -> dict:
    import mitsuba as mi

    mi.set_variant(variant)
    from tests.data.make_mitsuba_references import mitsuba_readable

    path = mitsuba_readable(path)
    mi.set_log_level(mi.LogLevel.Info)
    rss0 = rss_bytes()
    t0 = time.perf_counter()
    scene = mi.load_file(path)
    load_s = time.perf_counter() - t0
    rss1 = rss_bytes()
    tris = sum(s.face_count() for s in scene.shapes() if s.is_mesh())
    return {"triangles": tris, "load_s": load_s, "rss_growth_bytes_per_triangle": (rss1 - rss0) / tris}


def run_side(side: str, path: str, variant: str) -> dict:
    out = subprocess.run([sys.executable, __file__, path, "--side", side, "--variant", variant],
                         capture_output=True, text=True, timeout=1800)
    if out.returncode != 0:
        raise RuntimeError(f"{side} failed:\n{out.stderr[-4000:]}")
    result = json.loads(out.stdout.strip().splitlines()[-1])
    if side == "mitsuba":  # Mitsuba's log: "Embree ready.  (took 1.2s)" or "(took 350ms)"
        m = re.search(r"Embree ready\.\s*\(took ([0-9.]+)\s*(ms|s|m)\)", out.stdout + out.stderr)
        if m:
            result["embree_build_s"] = float(m.group(1)) * {"ms": 1e-3, "s": 1.0, "m": 60.0}[m.group(2)]
    return result


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("scene")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--variant", default="llvm_ad_rgb", help="Mitsuba 3 variant")
    ap.add_argument("--side", choices=("restir", "mitsuba"), help=argparse.SUPPRESS)
    ap.add_argument("--out", default="out/bench_scale.json")
    args = ap.parse_args()
    if args.side:  # one measurement in this fresh process; its last stdout line is the result
        r = restir_side(args.scene) if args.side == "restir" else mitsuba_side(args.scene, args.variant)
        sys.stdout.flush()
        print(json.dumps(r))
        return
    runs = {"restir": [], "mitsuba": []}
    for i in range(args.repeats):  # sides alternate, so a slow spell of the machine hits both
        for side in runs:
            runs[side].append(run_side(side, args.scene, args.variant))
            print(side, i, json.dumps(runs[side][-1]), flush=True)
    os.makedirs(os.path.dirname(args.out) or ".", exist_ok=True)
    with open(args.out, "w") as f:
        json.dump({"scene": args.scene, "variant": args.variant, "runs": runs}, f, indent=2)
    for side, rs in runs.items():
        keys = [k for k, v in rs[0].items() if isinstance(v, float)]
        print(side, ", ".join(f"{k} min {min(r[k] for r in rs):.3g}" for k in keys))


if __name__ == "__main__":
    main()
