"""ReSTIR DI on the many-light room: per-stage timings, and relMSE at equal time against direct
path tracing with NEE (`--method pt --max-depth 2 --set strategy=nee`), in one run.

    .venv/bin/python benchmarks/bench_restir_di.py --width 128 --height 128 --frames 16

Both methods render `frames` frames of the static scene; the quality measure is the relMSE of a
single frame, mean over pixels and channels of (x - ref)^2 / (ref^2 + 0.01), averaged over the
last half of the frames (ReSTIR DI's temporal history has built up by then). For each ReSTIR DI
configuration (CONFIGS) the path tracer gets as many spp per frame as fit into that
configuration's measured frame time. The reference is the path
tracer (MIS, max_depth 2) at `--ref-spp`.
"""
import argparse
import json

import numpy as np

import restir


# ReSTIR DI configurations compared in one run (each against PT-NEE at its own equal time)
CONFIGS = {
    "default": {},  # 32 light + 1 BSDF candidates, visibility-aware reuse
    "unshadowed": {"visibility": "shading", "candidates.bsdf": 0},  # V traced only at shading
    "8-candidates": {"candidates": 8},
}


def relmse(x, ref):
    return float(np.mean((x - ref) ** 2 / (ref ** 2 + 0.01)))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--scene", default="builtin:many-lights")
    ap.add_argument("--width", type=int, default=128)
    ap.add_argument("--height", type=int, default=128)
    ap.add_argument("--frames", type=int, default=16)
    ap.add_argument("--ref-spp", type=int, default=2048)
    ap.add_argument("--hide-emitters", action="store_true",
                    help="measure lighting only: directly visible emitters are black for every method")
    ap.add_argument("--configs", nargs="+", default=list(CONFIGS), choices=list(CONFIGS))
    ap.add_argument("--json")
    args = ap.parse_args()
    scene = restir.load_scene(args.scene, width=args.width, height=args.height)
    scene.hide_emitters = args.hide_emitters
    common = dict(width=args.width, height=args.height, max_depth=2, keep_frames=True)

    ref = restir.render(scene, restir.RenderConfig(spp=args.ref_spp, seed=99, **common)).image.astype(np.float64)
    restir.render(scene, restir.RenderConfig(method="restir-di", spp=1, frames=1, **common))  # compile, warm up
    restir.render(scene, restir.RenderConfig(spp=1, frames=1, settings={"strategy": "nee"}, **common))

    pilot = restir.render(scene, restir.RenderConfig(spp=4, frames=4, seed=2, settings={"strategy": "nee"}, **common))
    pt_ms_per_spp = pilot.stats["ms_per_frame"] / 4
    tail = slice(args.frames // 2, None)
    lights = int((scene.light_power() > 0).sum())
    print(f"{args.scene}: {lights} emissive triangles, {args.width}x{args.height}, {args.frames} frames, "
          f"emitters {'hidden' if args.hide_emitters else 'visible'}")
    print(f"path tracing, NEE, max_depth 2: {pt_ms_per_spp:.2f} ms per spp")
    results = {}
    for name in args.configs:
        settings = CONFIGS[name]
        di = restir.render(scene, restir.RenderConfig(method="restir-di", spp=1, frames=args.frames, seed=1,
                                                      settings=settings, **common))
        di_ms = di.stats["ms_per_frame"]
        spp_eq = max(1, int(round(di_ms / pt_ms_per_spp)))
        pt = restir.render(scene, restir.RenderConfig(spp=spp_eq, frames=args.frames, seed=3,
                                                      settings={"strategy": "nee"}, **common))
        e_di = np.mean([relmse(f, ref) for f in di.frame_images[tail].astype(np.float64)])
        e_pt = np.mean([relmse(f, ref) for f in pt.frame_images[tail].astype(np.float64)])
        e_di0 = relmse(di.frame_images[0].astype(np.float64), ref)
        stages = {k: v["total_ms"] / args.frames for k, v in di.stats["stages"].items()}
        print(f"\nReSTIR DI '{name}' {settings or '(defaults)'}: ms per frame by stage")
        print("  " + "  ".join(f"{k} {v:.2f}" for k, v in stages.items()) + f"  total {di_ms:.2f}")
        print(f"  PT-NEE at equal time: {spp_eq} spp per frame ({pt.stats['ms_per_frame']:.1f} ms per frame measured)")
        print(f"  relMSE per frame (frames {args.frames // 2}..{args.frames - 1}): ReSTIR DI {e_di:.4f}, "
              f"PT-NEE {e_pt:.4f}: ReSTIR DI is {e_pt / e_di:.2f}x lower (frame 0, no history yet: {e_di0:.4f})")
        results[name] = {"settings": settings, "di_stages_ms": stages, "di_ms_per_frame": di_ms,
                         "pt_spp_equal_time": spp_eq, "pt_ms_per_frame": pt.stats["ms_per_frame"],
                         "relmse_di": e_di, "relmse_pt": e_pt, "relmse_di_frame0": e_di0,
                         "counters": di.stats["counters"]}
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"pt_ms_per_spp": pt_ms_per_spp, "configs": results}, f, indent=2)


if __name__ == "__main__":
    main()
