"""Frames per second of `restir view`'s render loop, without a browser: what the viewer does for
each frame (restir/viewer/server.py) but sending it: render one frame of the method from the
camera (LiveRender.render), tonemap it, and encode it as the JPEG the page receives.

Two modes: *still*, the camera standing at the film's full size (the average accumulating), and
*moving*, the camera turning 0.5 degrees about the scene's centre every frame at the viewer's
reduced size (MOVING_SCALE of each side), as while the user drags. Each mode renders a few
frames to warm up (the kernels load, the history fills), then as many as fit in `seconds`.

    .venv/bin/python benchmarks/bench_view.py [--scene builtin:cornell-box] [--method restir-pt]
        [--size 256] [--width W] [--seconds 10] [--device cpu] [--memory SECONDS]

--memory SECONDS instead renders moving and still spans of 5 s in turn for that long (the
viewer's two film sizes, each with its integrator) and reports the process's resident memory
every 10 s: it must stay flat.
"""
import argparse
import io
import json
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

WARMUP = 4


def measure(scene: str = "builtin:cornell-box", method: str = "restir-pt", size: int = 256, seconds: float = 10.0,
            device: str = "cpu", width: int | None = None) -> dict:
    """Frames per second still (size x size, or width x size) and moving (each side scaled by
    MOVING_SCALE)."""
    from PIL import Image

    import restir
    from restir.camera_motion import camera_pose
    from restir.image_io import tonemap
    from restir.viewer.server import MOVING_SCALE
    from restir.viewer.live import LiveRender

    sc = restir.load_scene(scene)
    live = LiveRender(sc, method, device=device)
    out = {"scene": scene, "method": method, "device": device, "seconds": seconds}
    for mode in ("still", "moving"):
        scale = 1.0 if mode == "still" else MOVING_SCALE
        side, across = max(8, round(size * scale)), max(8, round((width or size) * scale))
        render_ms, encode_ms, n = [], [], 0
        t_end = None
        i = 0
        while True:
            pose = live.start_pose if mode == "still" else camera_pose(live.start_pose, sc.bounds(), "orbit",
                                                                         0.5, i)
            t0 = time.perf_counter()
            frame = live.render(pose, across, side)
            t1 = time.perf_counter()
            buf = io.BytesIO()
            Image.fromarray(tonemap(frame.average)).save(buf, format="JPEG", quality=90)
            t2 = time.perf_counter()
            i += 1
            if i == WARMUP:
                t_start = time.perf_counter()
                t_end = t_start + seconds
                continue
            if t_end is None:
                continue
            render_ms.append((t1 - t0) * 1e3)
            encode_ms.append((t2 - t1) * 1e3)
            n += 1
            if time.perf_counter() >= t_end:
                break
        wall = time.perf_counter() - t_start
        out[mode] = {"width": across, "height": side, "frames": n, "fps": n / wall,
                     "render_ms_median": float(np.median(render_ms)), "encode_ms_median": float(np.median(encode_ms)),
                     "bytes_per_pixel": frame.stats["bytes_per_pixel"]["total"]}
    return out


def memory(scene: str, method: str, size: int, seconds: float, device: str) -> dict:
    import restir
    from restir.camera_motion import camera_pose
    from restir.viewer.server import MOVING_SCALE
    from restir.viewer.live import LiveRender

    def rss_mib() -> float:
        with open("/proc/self/status") as f:
            return next(int(line.split()[1]) for line in f if line.startswith("VmRSS")) / 1024

    sc = restir.load_scene(scene)
    live = LiveRender(sc, method, device=device)
    samples, t0, i, frames = [], time.perf_counter(), 0, 0
    next_sample = t0
    while time.perf_counter() - t0 < seconds:
        moving = int((time.perf_counter() - t0) // 5) % 2 == 0
        side = max(8, round(size * MOVING_SCALE)) if moving else size
        pose = camera_pose(live.start_pose, sc.bounds(), "orbit", 0.5, i) if moving else live.start_pose
        live.render(pose, side, side)
        i += moving
        frames += 1
        if time.perf_counter() >= next_sample:
            samples.append((round(time.perf_counter() - t0, 1), round(rss_mib(), 1)))
            next_sample += 10.0
    rss = [m for _, m in samples]
    return {"scene": scene, "method": method, "device": device, "seconds": seconds, "frames": frames,
            "rss_mib": samples, "rss_first_mib": rss[0], "rss_last_mib": rss[-1], "rss_max_mib": max(rss)}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", default="builtin:cornell-box")
    ap.add_argument("--method", default="restir-pt")
    ap.add_argument("--size", type=int, default=256, help="the film's height (and width, without --width)")
    ap.add_argument("--width", type=int)
    ap.add_argument("--seconds", type=float, default=10.0)
    ap.add_argument("--device", default="cpu")
    ap.add_argument("--memory", type=float, metavar="SECONDS", help="the resident memory over this long instead")
    args = ap.parse_args()
    if args.memory:
        print(json.dumps(memory(args.scene, args.method, args.size, args.memory, args.device), indent=1))
        return 0
    print(json.dumps(measure(args.scene, args.method, args.size, args.seconds, args.device, args.width), indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
