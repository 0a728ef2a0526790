"""ReSTIR DI on the many-light room: per-stage timings, and relMSE at equal time against direct
path tracing with NEE (`--method pt --max-depth 2 --set strategy=nee`), in one run.

    .venv/bin/python benchmarks/bench_restir_di.py --width 128 --height 128 --frames 16

All methods render `frames` frames of the static scene; the quality measure is the relMSE of a
single frame, mean over pixels and channels of (x - ref)^2 / (ref^2 + 0.01), averaged over the
last half of the frames (ReSTIR DI's temporal history has built up by then). For each ReSTIR DI
configuration (CONFIGS), two baselines get that configuration's measured frame time:

- PT-NEE: as many camera samples per pixel (spp) as fit, one light sample each;
- direct NEE: one camera sample per pixel, as ReSTIR DI has, and as many light samples at its
  primary hit (`nee.samples`, Mitsuba's `direct` integrator's emitter samples) as fit. With
  emitters seen directly this separates the light transport from antialiasing the emitters.

All three render with the same seed: they share their camera samples (every method draws camera
rays from one stream), so the error of the directly seen emitters, the same estimator in all
of them, is common to ReSTIR DI and direct NEE instead of adding independent noise to each.
The reference is the path tracer (MIS, max_depth 2) at `--ref-spp`, with another seed.
`--saturation` sets the light colours (1: each channel uniform in [0.2, 1]; 0: grey, same
luminance): ReSTIR DI resamples by luminance, so with coloured lights each channel keeps the
ratio of the light's colour to its luminance as noise, which averaging many light samples
removes and resampling does not.
"""
import argparse
import json

import numpy as np

import restir


# ReSTIR DI configurations compared in one run (each against PT-NEE at its own equal time)
CONFIGS = {
    "default": {},  # 32 light + 1 BSDF candidates, visibility-aware reuse, 3 neighbours in 30 px, 2 rounds
    # 30 px is the literature's radius at 1920x1080; at 128x128 it reaches a quarter of the image
    "radius-10": {"spatial.radius": 10.0},
    "radius-10-unshadowed": {"spatial.radius": 10.0, "visibility": "shading", "candidates.bsdf": 0},
    # cheaper per frame: 8 light candidates, one spatial round
    "radius-10-8-candidates-1-round": {"spatial.radius": 10.0, "candidates": 8, "spatial.rounds": 1},
    "radius-10-4-candidates-1-round-k2": {"spatial.radius": 10.0, "candidates": 4, "spatial.rounds": 1,
                                          "spatial.neighbors": 2},
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
    ap.add_argument("--saturation", type=float, default=1.0, help="light colour saturation (builtin many-lights)")
    ap.add_argument("--configs", nargs="+", default=list(CONFIGS), choices=list(CONFIGS))
    ap.add_argument("--json")
    args = ap.parse_args()
    extra = {"saturation": args.saturation} if args.scene == "builtin:many-lights" else {}
    scene = restir.load_scene(args.scene, width=args.width, height=args.height, **extra)
    scene.hide_emitters = args.hide_emitters
    common = dict(width=args.width, height=args.height, max_depth=2, keep_frames=True)

    ref = restir.render(scene, restir.RenderConfig(spp=args.ref_spp, seed=99, **common)).image.astype(np.float64)
    restir.render(scene, restir.RenderConfig(method="restir-di", spp=1, frames=1, **common))  # compile, warm up

    def nee(spp, light_samples, frames, seed):
        return restir.render(scene, restir.RenderConfig(spp=spp, frames=frames, seed=seed, **common, settings={
            "strategy": "nee", "nee.samples": light_samples}))

    nee(1, 2, 1, 0)  # compile, warm up
    pt_ms_per_spp = nee(4, 1, 4, 2).stats["ms_per_frame"] / 4
    # direct NEE frame time, linear in the light samples N: a + b N
    t1, t16 = (nee(1, n, 4, 2).stats["ms_per_frame"] for n in (1, 16))
    nee_ms_per_light = (t16 - t1) / 15
    nee_ms_base = t1 - nee_ms_per_light
    tail = slice(args.frames // 2, None)
    lights = int((scene.light_power() > 0).sum())
    print(f"{args.scene}: {lights} emissive triangles, {args.width}x{args.height}, {args.frames} frames, "
          f"emitters {'hidden' if args.hide_emitters else 'visible'}, light colour saturation {args.saturation}")
    print(f"path tracing, NEE, max_depth 2: {pt_ms_per_spp:.2f} ms per spp; direct NEE at 1 spp: "
          f"{nee_ms_base:.2f} ms + {nee_ms_per_light:.2f} ms per light sample")
    results = {}
    for name in args.configs:
        settings = CONFIGS[name]
        di = restir.render(scene, restir.RenderConfig(method="restir-di", spp=1, frames=args.frames, seed=1,
                                                      settings=settings, **common))
        di_ms = di.stats["ms_per_frame"]
        spp_eq = max(1, int(round(di_ms / pt_ms_per_spp)))
        n_eq = max(1, int(round((di_ms - nee_ms_base) / nee_ms_per_light)))
        pt = nee(spp_eq, 1, args.frames, 1)
        direct = nee(1, n_eq, args.frames, 1)
        e_di, e_pt, e_direct = (np.mean([relmse(f, ref) for f in r.frame_images[tail].astype(np.float64)])
                                for r in (di, pt, direct))
        e_di0 = relmse(di.frame_images[0].astype(np.float64), ref)
        stages = {k: v["total_ms"] / args.frames for k, v in di.stats["stages"].items()}
        print(f"\nReSTIR DI '{name}' {settings or '(defaults)'}: ms per frame by stage")
        print("  " + "  ".join(f"{k} {v:.2f}" for k, v in stages.items()) + f"  total {di_ms:.2f}")
        print(f"  relMSE per frame (frames {args.frames // 2}..{args.frames - 1}): ReSTIR DI {e_di:.4f} "
              f"(frame 0, no history yet: {e_di0:.4f})")
        print(f"  PT-NEE at equal time, {spp_eq} spp ({pt.stats['ms_per_frame']:.1f} ms per frame measured): "
              f"{e_pt:.4f}, ReSTIR DI is {e_pt / e_di:.2f}x lower")
        print(f"  direct NEE at equal time, 1 spp x {n_eq} light samples ({direct.stats['ms_per_frame']:.1f} ms per "
              f"frame measured): {e_direct:.4f}, ReSTIR DI is {e_direct / e_di:.2f}x lower")
        results[name] = {"settings": settings, "di_stages_ms": stages, "di_ms_per_frame": di_ms,
                         "pt_spp_equal_time": spp_eq, "pt_ms_per_frame": pt.stats["ms_per_frame"],
                         "direct_light_samples_equal_time": n_eq, "direct_ms_per_frame": direct.stats["ms_per_frame"],
                         "relmse_di": e_di, "relmse_pt": e_pt, "relmse_direct": e_direct, "relmse_di_frame0": e_di0,
                         "counters": di.stats["counters"]}
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"pt_ms_per_spp": pt_ms_per_spp, "direct_ms_base": nee_ms_base,
                       "direct_ms_per_light_sample": nee_ms_per_light, "configs": results}, f, indent=2)


if __name__ == "__main__":
    main()
