"""Spatial reuse under a moving camera, after the denoiser.

`restir compare` measures a still camera: one reference serves every frame. Under a still camera
temporal reuse alone has a full history at every pixel, and ReSTIR PT's spatial reuse does not pay
after the denoiser (docs/guide/decorrelation.md, section 8). A moving camera uncovers pixels without
history every frame, which is where spatial reuse is expected to matter. This script measures it:

- the camera moves by `camera_motion` (orbit: `--speed` degrees a frame) for `--frames` frames;
- each measured frame (after `--warmup`) has its own reference, the path tracer at `--ref-spp`
  at that frame's pose (cached in `--cache`), and its own denoiser guides (the first hit's albedo
  and normal at that pose, as `restir compare` computes them for frame 0);
- every method renders the same frames; per frame, relMSE raw and after Open Image Denoise;
- equal time as `restir compare` reads it: each method's frame time (median of the frames after
  the first) as path-tracer spp on a line through the path tracer's own frame times (1, 2, 3 spp
  here), the path tracer's denoised error interpolated log-log between the whole spp on both sides.

    RESTIR_CPU_THREADS=1 taskset -c 0 .venv/bin/python benchmarks/bench_motion.py --scene builtin:indirect-room \\
        --speed 1 --json benchmarks/results/restir_pt/motion_room.json
"""
import argparse
import json
import os
import statistics
import sys
import time
from types import SimpleNamespace

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))

import numpy as np  # noqa: E402

import restir  # noqa: E402
from restir.api import make_integrator, sized_scene  # noqa: E402
from restir.compare.denoise import Denoiser, require_oidn  # noqa: E402
from restir.compare.equal_time import FrameTimeFit  # noqa: E402
from restir.compare.headline import at_spp  # noqa: E402
from restir.compare.metrics import relmse  # noqa: E402
from restir.config import RenderConfig  # noqa: E402

METHODS = [("pt", "pt", 1, {}), ("pt:spp=2", "pt", 2, {}), ("pt:spp=3", "pt", 3, {}),
           ("restir-pt", "restir-pt", 1, {}), ("restir-pt:spatial.radius=48", "restir-pt", 1, {"spatial.radius": 48}),
           ("restir-pt:spatial.rounds=0", "restir-pt", 1, {"spatial.rounds": 0})]


def config(args, method, spp, settings, seed):
    return RenderConfig(method=method, spp=spp, width=args.size, height=args.size, seed=seed, settings=settings,
                        camera_motion=args.motion, camera_speed=args.speed)


def guides(integ, frame):
    """The denoiser's guides at `frame`'s pose: restir.aov's kernel with that frame's camera."""
    import warp as wp

    from restir.aov import AOV_SAMPLES, AOVS, aov_kernel
    from restir.parallel import launch_pixels

    n = integ.num_pixels
    out = {k: wp.zeros(n, dtype=wp.vec3, device=integ.device) for k in AOVS}
    launch_pixels(aov_kernel, n, [integ.dscene.scene, integ.camera(frame), wp.uint32(integ.settings.seed), AOV_SAMPLES],
                  [out["albedo"], out["normal"]], integ.device, integ.slices)
    shape = (integ.height, integ.width, 3)
    return Denoiser(np.clip(out["albedo"].numpy().reshape(shape), 0.0, 1.0).astype(np.float32),
                    out["normal"].numpy().reshape(shape).astype(np.float32))


def references(scene, args, frames):
    """The path tracer at --ref-spp at each measured frame's pose (cached), and the guides there."""
    path = os.path.join(args.cache, f"{args.name}_{args.motion}{args.speed:g}_{args.size}_{args.ref_spp}_"
                                     f"{args.frames}.npz")
    integ = make_integrator(sized_scene(scene, config(args, "pt", args.ref_spp, {}, 99)),
                            config(args, "pt", args.ref_spp, {}, 99))
    dens = {f: guides(integ, f) for f in frames}
    if os.path.exists(path):
        data = np.load(path)
        return {f: data[f"f{f}"] for f in frames}, dens
    refs = {}
    for f in frames:
        t = time.perf_counter()
        refs[f] = np.asarray(integ.render_frame(f)[0], np.float64)
        print(f"  reference frame {f}: {time.perf_counter() - t:.0f} s", flush=True)
    os.makedirs(args.cache, exist_ok=True)
    np.savez_compressed(path, **{f"f{f}": v for f, v in refs.items()})
    return refs, dens


def run(scene, args, method, spp, settings, refs, dens):
    cfg = config(args, method, spp, settings, args.seed)
    integ = make_integrator(sized_scene(scene, cfg), cfg)
    ms, raw, den = [], [], []
    for f in range(args.frames):
        t = time.perf_counter()
        image = np.asarray(integ.render_frame(f)[0], np.float64)
        if f > 0:  # the first frame compiles and starts without history
            ms.append((time.perf_counter() - t) * 1e3)
        if f in refs:
            raw.append(relmse(image, refs[f]))
            den.append(relmse(dens[f](image), refs[f]))
    return {"ms_per_frame": statistics.median(ms), "raw": float(np.mean(raw)), "denoised": float(np.mean(den)),
            "denoised_by_frame": den}


def at_equal_time(rows):
    """Each non-pt row against the path tracer at its frame time, as `restir compare` reads it
    (equal_time.FrameTimeFit, headline.at_spp), the line through the pt rows' own frame times
    (least squares) and the pt rows on both sides of the frame's worth (the nearest two outside
    them: extrapolated)."""
    pts = {1 if k == "pt" else int(k.split("spp=")[1]): r for k, r in rows.items() if k.startswith("pt")}
    ks = sorted(pts)
    mx = sum(ks) / len(ks)
    my = sum(pts[k]["ms_per_frame"] for k in ks) / len(ks)
    b = sum((k - mx) * (pts[k]["ms_per_frame"] - my) for k in ks) / sum((k - mx) ** 2 for k in ks)
    fit = FrameTimeFit(my - b * mx, b, [(k, pts[k]["ms_per_frame"]) for k in ks])
    results = {k: SimpleNamespace(spp=k, metrics={"relmse_denoised_frame": pts[k]["denoised"]}) for k in ks}
    for label, r in rows.items():
        if label.startswith("pt"):
            continue
        spp = fit.spp_at(r["ms_per_frame"])
        i = max(0, min(len(ks) - 2, max([j for j, k in enumerate(ks) if k <= spp] or [0])))
        e = at_spp(results[ks[i]], results[ks[i + 1]], spp, "relmse_denoised_frame")
        r["spp"], r["pt_denoised_there"], r["factor_denoised"] = spp, e, e / r["denoised"]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--scene", default="builtin:indirect-room")
    ap.add_argument("--motion", default="orbit", choices=["orbit", "dolly"])
    ap.add_argument("--speed", type=float, default=1.0, help="degrees a frame (orbit), scene sizes a frame (dolly)")
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--frames", type=int, default=16)
    ap.add_argument("--warmup", type=int, default=4)
    ap.add_argument("--ref-spp", type=int, default=1024)
    ap.add_argument("--seeds", type=int, nargs="+", default=[1])
    ap.add_argument("--cache", default="out/motion_refs")
    ap.add_argument("--json")
    args = ap.parse_args()
    require_oidn()
    args.name = args.scene.replace("builtin:", "").replace("/", "_")
    scene = restir.load_scene(args.scene)
    measured = list(range(args.warmup, args.frames))
    refs, dens = references(scene, args, measured)
    out = {"args": vars(args), "seeds": {}}
    for seed in args.seeds:
        args.seed = seed
        rows = {label: run(scene, args, method, spp, settings, refs, dens) for label, method, spp, settings in METHODS}
        at_equal_time(rows)
        out["seeds"][seed] = rows
        print(f"\n{args.name}, {args.motion} {args.speed:g} a frame, {args.size}x{args.size}, frames "
              f"{args.warmup}-{args.frames - 1}, seed {seed}")
        for label, r in rows.items():
            extra = "" if label.startswith("pt") else (f" = {r['spp']:.2f} spp; the path tracer there "
                                                       f"{r['pt_denoised_there']:.4g}: {r['factor_denoised']:.2f}x")
            print(f"  {label:30s} {r['ms_per_frame']:6.1f} ms raw {r['raw']:.4g} denoised {r['denoised']:.4g}{extra}",
                  flush=True)
        if args.json:
            with open(args.json, "w") as f:
                json.dump(out, f, indent=2)


if __name__ == "__main__":
    main()
