"""ReSTIR DI defaults: how much reuse lowers the per-frame error, over temporal.cap x
spatial.radius x spatial.rounds x resolution, raw and after Open Image Denoise.

    .venv/bin/python benchmarks/bench_di_defaults.py --phase rules       # the grid the defaults came from
    .venv/bin/python benchmarks/bench_di_defaults.py --phase candidates rules_timing --sizes 128 256 \
        --cap 2 --rounds 1 --rule-r1080 5 --rule-floor 5 --timing-rules 2,2,8,8 2,1,8,8
    .venv/bin/python benchmarks/bench_di_defaults.py --phase defaults    # the shipped defaults
    .venv/bin/python benchmarks/bench_di_defaults.py --phase all         # the older, wider sweep

Rows, references and results go to --out (default benchmarks/results/di_defaults/: results.json,
ref_*.npz). The whole sweep took about 24 minutes on 2 cores (shared with other jobs); rerun, it
reads its rows from results.json and only the uncached phases (timing, long, overflow, defaults)
render again.

Quality: relMSE of single frames, mean over pixels and channels of (x - ref)^2 / (ref^2 + 0.01),
averaged over frames 8..15 of 16 (the temporal history has built up), as bench_restir_di.py
measures it. Every configuration is compared with *no reuse at the same candidate count*
(`temporal=false spatial.rounds=0`, same seed): ratio = relMSE(no reuse) / relMSE(config), so
the ratio isolates what reuse buys. Emitters are hidden (lighting only). The reference is the
path tracer (MIS, max_depth 2, the same image in expectation) at high spp, cached as .npz; its
own noise adds `ref_floor` = mean(Var[ref] / (ref^2 + 0.01)) to every relMSE (printed). Each
row also holds the same relMSE of the frames after Open Image Denoise (albedo and normal guides;
NaN without pyoidn): spatial reuse copies a neighbour's sample, and a small disk puts the copies
side by side, an error the per-frame relMSE counts like any other but the denoiser keeps.

Radii are given as a fraction of the image height (radius_px = frac * height); the table
prints both the pixels and r1080 = frac * 1080, the radius the same rule gives at 1080 lines.
`temporal.cap = 0` means no cap; rows whose non-finite counters are not zero are flagged.

Phases (each row is cached in the JSON, keyed by scene/resolution/seed/settings, so a phase
can be rerun or resumed; `--fresh` recomputes):
  main128   many-lights 128x128, seeds 1 and 2: no reuse, temporal only, spatial only and the
            full cap x radius x rounds grid at 32 candidates; a smaller grid at 8 candidates
  res64     many-lights 64x64, seeds 1 and 2, the full grid at 32 candidates
  res256    many-lights 256x256, seed 1: the best cap of main128 and cap 20, 6 radii
  small256  many-lights 256x256, seed 1: radii of 1.5-3.6 px (below the res256 grid)
  cornell   cornell-box 128x128, seeds 1 and 2: a coarse grid
  grey      many-lights with grey lights (saturation 0), 128x128, seed 1: a coarse grid
            (coloured lights leave a colour-to-luminance noise floor that reuse cannot lower)
  floor     1 camera sample x 256 NEE light samples per pixel and frame: the camera-jitter error
            that no light reuse removes (bounds the ratio)
  proposal  the proposed defaults (--rule-r1080, --rule-floor, --cap, --rounds) at 64/128/256
            on both scenes, against no reuse and the first defaults
  timing    frame time of five configurations at 128x128 (3 alternating repeats, medians)
  res512    many-lights 512x512, seed 1: cap 5, 2 rounds, radius 3, 7.1 and 14.2 px
  long      many-lights 128x128, 64 frames: temporal drift by cap
  overflow  cap 0 with spatial reuse over 48 frames, 64x64: max M and non-finite counters per frame
  defaults  the shipped defaults (DISettings, nothing set but the candidates) at 64/128/256
            against no reuse: the check that reuse lowers per-frame relMSE at least 2x at 128x128
  rules     both scenes at 128, 64 and 256 lines, seeds 1 and 2: cap x radius in px x 1 or 2
            rounds and temporal reuse alone, raw and denoised gain (the radii include 15 px and
            the rule before it, max(2, 15 x height / 1080)); rules512: the same at 512, seed 1
  candidates  the rules compared (15 px with cap 5 and 2 rounds; max(2, 15 h / 1080) px with cap
            5 and 2 rounds; the proposal and --timing-rules) at --sizes on both scenes
  rules_timing  frame time of the same rules and no reuse at --sizes as ratios to the 15 px rule,
            each of --repeats repeats rendering every rule in turn (medians and ranges)

A rule's radius is max(--rule-floor, --rule-r1080 x height / 1080) px: --rule-r1080 5
--rule-floor 5 is 5 px up to 1080 lines, scaled with the height above.
"""
import argparse
import json
import os
import subprocess
import time

import numpy as np

import restir

OUT_DIR = os.path.join(os.path.dirname(os.path.abspath(__file__)), "results", "di_defaults")
FRAMES = 16
TAIL = slice(8, 16)
CAPS = [1, 2, 5, 10, 20, 0]  # 0: no cap
# radii as fractions of the height; in pixels at 128 lines: 1.5 2 3 3.56 5 7 10 20 30
# (3.56 px at 128 = 30 px at 1080: the literature's radius scaled with the image)
FRACS = [1.5 / 128, 2 / 128, 3 / 128, 30 / 1080, 5 / 128, 7 / 128, 10 / 128, 20 / 128, 30 / 128]
FRACS_256 = [1.5 / 128, 3 / 128, 30 / 1080, 5 / 128, 10 / 128, 20 / 128]
REF_SPP = {64: 8192, 128: 4096, 256: 2048, 512: 1024}
NO_REUSE = {"temporal": False, "spatial.rounds": 0}
# the defaults before the first sweep (cap 20, the literature's 30 px at any size), spelled out so that the
# row keeps its meaning when the defaults change
FIRST = {"temporal": True, "temporal.cap": 20.0, "spatial.rounds": 2, "spatial.neighbors": 3, "spatial.radius": 30.0}


def relmse(x, ref):
    return float(np.mean((x - ref) ** 2 / (ref ** 2 + 0.01)))


class Bench:
    def __init__(self, path, fresh):
        self.path = path
        self.data = {"meta": {}, "refs": {}, "rows": {}}
        if os.path.exists(path) and not fresh:
            with open(path) as f:
                self.data = json.load(f)
        self.scenes = {}
        self.refs = {}
        self.denoisers = {}

    def save(self):
        tmp = self.path + ".tmp"
        with open(tmp, "w") as f:
            json.dump(self.data, f, indent=1)
        os.replace(tmp, self.path)

    def scene(self, name, res):
        key = (name, res)
        if key not in self.scenes:
            extra = {"saturation": 0.0} if name == "many-lights-grey" else {}
            builtin = "many-lights" if name == "many-lights-grey" else name
            s = restir.load_scene(f"builtin:{builtin}", width=res, height=res, **extra)
            s.hide_emitters = True
            self.scenes[key] = s
        return self.scenes[key]

    def ref(self, name, res):
        key = (name, res)
        if key in self.refs:
            return self.refs[key]
        spp = REF_SPP[res]
        path = os.path.join(OUT_DIR, f"ref_{name}_{res}_{spp}spp.npz")
        if os.path.exists(path):
            z = np.load(path)
            img, var = z["image"].astype(np.float64), z["var"].astype(np.float64)
        else:
            t = time.perf_counter()
            r = restir.render(self.scene(name, res), restir.RenderConfig(
                method="pt", spp=spp, frames=1, seed=99, max_depth=2, width=res, height=res))
            img, var = r.image.astype(np.float64), r.variance_of_mean
            np.savez(path, image=img, var=var)
            print(f"  reference {name} {res}x{res}: PT MIS max_depth 2, {spp} spp, "
                  f"{time.perf_counter() - t:.0f} s", flush=True)
        floor = float(np.mean(var / (img ** 2 + 0.01)))
        self.data["refs"][f"{name}/{res}"] = {"spp": spp, "ref_floor": floor, "file": path,
                                             "mean": float(img.mean())}
        self.refs[key] = (img, floor)
        return self.refs[key]

    def denoiser(self, name, res):
        """Open Image Denoise with the scene's albedo and normal guides (None without pyoidn)."""
        key = (name, res)
        if key not in self.denoisers:
            from restir.config import ConfigError

            try:
                from restir.compare.denoise import Denoiser

                self.denoisers[key] = Denoiser.for_scene(self.scene(name, res), restir.RenderConfig(
                    method="pt", spp=1, frames=1, width=res, height=res))
            except ConfigError:
                self.denoisers[key] = None
        return self.denoisers[key]

    def run(self, name, res, seed, settings, fresh=False):
        key = f"{name}/{res}/seed{seed}/" + json.dumps(settings, sort_keys=True)
        if key in self.data["rows"] and not fresh:
            return self.data["rows"][key]
        ref, floor = self.ref(name, res)
        t = time.perf_counter()
        r = restir.render(self.scene(name, res), restir.RenderConfig(
            method="restir-di", spp=1, frames=FRAMES, seed=seed, width=res, height=res, keep_frames=True,
            settings=settings))
        frames = r.frame_images.astype(np.float64)
        per_frame = [relmse(f, ref) for f in frames]
        den = self.denoiser(name, res)
        denoised = [relmse(den(f), ref) for f in frames[TAIL]] if den else [float("nan")]
        c = r.stats["counters"]
        row = {"scene": name, "res": res, "seed": seed, "settings": settings,
               "relmse": float(np.mean(per_frame[TAIL])), "relmse_frames": per_frame,
               "relmse_denoised": float(np.mean(denoised)), "radius_px": r.stats["settings"]["spatial.radius"],
               "ms_per_frame": r.stats["ms_per_frame"], "wall_s": time.perf_counter() - t,
               "nonfinite": int(c.get("nonfinite_weights", 0) + c.get("nonfinite_outputs", 0)),
               "counters": c}
        self.data["rows"][key] = row
        self.save()
        return row


def combo(cap, frac, rounds, res, cands):
    s = {"candidates": cands, "temporal.cap": float(cap), "spatial.radius": frac * res, "spatial.rounds": rounds}
    return s


def describe(s, res):
    """Short label of a settings dict (defaults filled in as DISettings has them)."""
    from restir.integrators.common.reuse_domains import spatial_radius_for
    from restir.integrators.restir_di.pipeline import DISettings

    d = DISettings()
    t = s.get("temporal", d.temporal)
    rounds = s.get("spatial.rounds", d.spatial.rounds)
    rad = s.get("spatial.radius", "auto")
    if rad == "auto":
        rad = spatial_radius_for(d.spatial.radius_at_1080, res)
    parts = []
    parts.append(f"T cap {s.get('temporal.cap', d.temporal_cap):g}" if t else "T off")
    if rounds:
        parts.append(f"S {rounds}x r {rad:.2f}px ({rad / res:.4f} h, r1080 {rad / res * 1080:.1f})")
    else:
        parts.append("S off")
    return ", ".join(parts)


def table(bench, name, res, seeds, configs, cands, title, fresh=False):
    """Run configs (list of settings) and the no-reuse baseline; print and return summary rows
    (fresh: render the configs again, e.g. when they rely on defaults that may have changed)."""
    print(f"\n== {title}: {name} {res}x{res}, {cands} candidates, seeds {seeds}, frames 8..15 of 16 ==",
          flush=True)
    base = [bench.run(name, res, sd, {"candidates": cands, **NO_REUSE}) for sd in seeds]
    e0 = float(np.mean([b["relmse"] for b in base]))
    _, floor = bench.ref(name, res)
    print(f"  no reuse: relMSE {e0:.4f} ({base[0]['ms_per_frame']:.1f} ms/frame); reference floor {floor:.5f}")
    out = []
    for s in configs:
        rows = [bench.run(name, res, sd, s, fresh=fresh) for sd in seeds]
        e = float(np.mean([r["relmse"] for r in rows]))
        per_seed = [b["relmse"] / r["relmse"] if r["relmse"] > 0 else float("inf") for b, r in zip(base, rows)]
        nf = sum(r["nonfinite"] for r in rows)
        ms = float(np.mean([r["ms_per_frame"] for r in rows]))
        summ = {"scene": name, "res": res, "cands": cands, "settings": s, "label": describe(s, res),
                "relmse": e, "ratio": e0 / e if e > 0 else float("inf"),
                "ratio_floor_corrected": (e0 - floor) / (e - floor) if e > floor else float("inf"),
                "ratio_per_seed": per_seed, "ms_per_frame": ms, "nonfinite": nf, "relmse_no_reuse": e0}
        out.append(summ)
        flag = f"  NONFINITE {nf}" if nf else ""
        print(f"  {summ['label']:<58} relMSE {e:.4f}  ratio {summ['ratio']:5.2f}x "
              f"(seeds {' '.join(f'{x:.2f}' for x in per_seed)})  {ms:6.1f} ms{flag}", flush=True)
    bench.data.setdefault("summaries", {})[f"{title}|{name}|{res}|{cands}"] = out
    bench.save()
    return out


def grid(res, cands, caps, fracs, rounds_list):
    return [combo(c, f, r, res, cands) for r in rounds_list for c in caps for f in fracs]


def separate(res, cands, caps, fracs, rounds_list):
    temporal = [{"candidates": cands, "temporal.cap": float(c), "spatial.rounds": 0} for c in caps]
    spatial = [{"candidates": cands, "temporal": False, "spatial.radius": f * res, "spatial.rounds": r}
               for r in rounds_list for f in fracs]
    return temporal + spatial


def print_matrix(summ, caps, fracs, rounds_list, res):
    """Ratio matrix: rows cap, columns radius, one block per rounds."""
    by = {(s["settings"].get("temporal.cap"), round(s["settings"].get("spatial.radius", 0) / res, 6),
           s["settings"].get("spatial.rounds")): s for s in summ if s["settings"].get("temporal", True)}
    for r in rounds_list:
        print(f"  ratio no-reuse/config, {r} round(s); columns: radius px at {res} (r1080)")
        print("    cap  " + " ".join(f"{f * res:6.2f}" for f in fracs))
        print("         " + " ".join(f"({f * 1080:4.0f})" for f in fracs))
        for c in caps:
            cells = []
            for f in fracs:
                s = by.get((float(c), round(f, 6), r))
                cells.append(f"{s['ratio']:6.2f}" + ("!" if s and s["nonfinite"] else "") if s else "     -")
            print(f"    {c if c else 'none':>4} " + " ".join(cells))


def best_caps(bench, k=2):
    summ = bench.data.get("summaries", {}).get("grid|many-lights|128|32")
    if not summ:
        return [2, 5]
    best = {}
    for s in summ:
        c = s["settings"]["temporal.cap"]
        if c == 0:
            continue
        best[c] = max(best.get(c, 0), s["ratio"])
    return [int(c) for c, _ in sorted(best.items(), key=lambda kv: -kv[1])[:k]]


def phase_main128(bench):
    res, seeds = 128, [1, 2]
    table(bench, "many-lights", res, seeds, [{"candidates": 32, **FIRST}], 32, "first defaults")
    table(bench, "many-lights", res, seeds, separate(res, 32, CAPS, FRACS, [1, 2]), 32, "separate")
    g = table(bench, "many-lights", res, seeds, grid(res, 32, CAPS, FRACS, [1, 2]), 32, "grid")
    print_matrix(g, CAPS, FRACS, [1, 2], res)
    f8 = [3 / 128, 5 / 128, 10 / 128]
    g8 = table(bench, "many-lights", res, seeds, separate(res, 8, [2, 5, 20], f8, [1]) +
               grid(res, 8, [2, 5, 10, 20], f8, [1, 2]), 8, "grid")
    print_matrix(g8, [2, 5, 10, 20], f8, [1, 2], res)


def phase_res64(bench):
    res, seeds = 64, [1, 2]
    table(bench, "many-lights", res, seeds, [{"candidates": 32, **FIRST}], 32, "first defaults")
    table(bench, "many-lights", res, seeds, separate(res, 32, CAPS, FRACS, [1, 2]), 32, "separate")
    g = table(bench, "many-lights", res, seeds, grid(res, 32, CAPS, FRACS, [1, 2]), 32, "grid")
    print_matrix(g, CAPS, FRACS, [1, 2], res)


def phase_res256(bench):
    res, seeds = 256, [1]
    caps = sorted(set(best_caps(bench, 1)) | {20}, key=lambda c: CAPS.index(c))
    print(f"\n256x256: caps {caps} (the best of the 128 grid, and 20)")
    table(bench, "many-lights", res, seeds, [{"candidates": 32, **FIRST}], 32, "first defaults")
    table(bench, "many-lights", res, seeds, separate(res, 32, [2, 5, 20], [3 / 128, 30 / 1080, 5 / 128, 10 / 128], [1, 2]),
          32, "separate")
    g = table(bench, "many-lights", res, seeds, grid(res, 32, caps, FRACS_256, [1, 2]), 32, "grid")
    print_matrix(g, caps, FRACS_256, [1, 2], res)


def scene_sweep(bench, name, res, seeds, fr, caps, separate_caps):
    """Today's defaults, then temporal-only / spatial-only rows, then the cap x radius x rounds grid."""
    table(bench, name, res, seeds, [{"candidates": 32, **FIRST}], 32, "first defaults")
    table(bench, name, res, seeds, separate(res, 32, separate_caps, fr, [1, 2]), 32, "separate")
    g = table(bench, name, res, seeds, grid(res, 32, caps, fr, [1, 2]), 32, "grid")
    print_matrix(g, caps, fr, [1, 2], res)


def phase_cornell(bench):
    scene_sweep(bench, "cornell-box", 128, [1, 2], [2 / 128, 3 / 128, 5 / 128, 10 / 128, 30 / 128], [1, 2, 5, 10, 20],
                CAPS)


def phase_grey(bench):
    """Grey lights (saturation 0, same luminance): no colour-to-luminance noise floor."""
    caps = [2, 5, 20]
    scene_sweep(bench, "many-lights-grey", 128, [1], [1.5 / 128, 3 / 128, 30 / 1080, 5 / 128, 10 / 128, 30 / 128],
                caps, caps)


def phase_small256(bench):
    """256x256: radii below the grid's smallest (3 px), to locate the optimum in pixels."""
    res, seeds = 256, [1]
    fr = [1.5 / 256, 2 / 256, 3 / 256, 15 / 1080]
    table(bench, "many-lights", res, seeds, [combo(c, f, 2, res, 32) for c in (2, 5) for f in fr] +
          [combo(5, f, 1, res, 32) for f in (2 / 256, 3 / 256, 30 / 1080)], 32, "small radii")


def phase_floor(bench, light_samples=256):
    """What reuse cannot remove: one jittered camera sample per pixel and frame, as ReSTIR DI has,
    with `light_samples` NEE light samples at its primary hit (direct lighting nearly exact there;
    the colour of many lights is averaged out too). Its per-frame relMSE is the error left by the
    camera jitter (antialiasing), and no-reuse / it bounds the ratio any reuse can reach."""
    print(f"\n== floor: PT NEE, 1 camera sample x {light_samples} light samples per pixel and frame ==")
    out = {}
    for name, res in (("many-lights", 64), ("many-lights", 128), ("many-lights", 256), ("many-lights-grey", 128),
                      ("cornell-box", 128)):
        key = f"floor/{name}/{res}/{light_samples}"
        if key not in bench.data["rows"]:
            ref, rfloor = bench.ref(name, res)
            r = restir.render(bench.scene(name, res), restir.RenderConfig(
                method="pt", spp=1, frames=FRAMES, seed=1, max_depth=2, width=res, height=res, keep_frames=True,
                settings={"strategy": "nee", "nee.samples": light_samples}))
            per_frame = [relmse(f, ref) for f in r.frame_images.astype(np.float64)]
            bench.data["rows"][key] = {"scene": name, "res": res, "relmse": float(np.mean(per_frame[TAIL])),
                                       "ms_per_frame": r.stats["ms_per_frame"]}
            bench.save()
        e = bench.data["rows"][key]["relmse"]
        nr = bench.run(name, res, 1, {"candidates": 32, **NO_REUSE})["relmse"]
        out[f"{name}/{res}"] = {"relmse_floor": e, "relmse_no_reuse_seed1": nr, "max_ratio": nr / e}
        print(f"  {name} {res}x{res}: floor relMSE {e:.4f}; no reuse (32 candidates, seed 1) {nr:.4f}; "
              f"largest possible ratio {nr / e:.2f}x", flush=True)
    bench.data["floor"] = out
    bench.save()


def phase_timing(bench, res=128, repeats=3):
    """Frame time by configuration (alternating repeats, medians); the sweep's ms/frame figures
    are taken while other work may share the CPU, these are not cached."""
    print(f"\n== timing: many-lights {res}x{res}, 32 candidates, {FRAMES} frames, {repeats} alternating repeats ==")
    r2 = 2.0
    configs = {"no reuse": NO_REUSE, "temporal cap 5 only": {"temporal.cap": 5.0, "spatial.rounds": 0},
               "T cap 5 + S 1 round r 2 px": {"temporal.cap": 5.0, "spatial.rounds": 1, "spatial.radius": r2},
               "T cap 5 + S 2 rounds r 2 px": {"temporal.cap": 5.0, "spatial.rounds": 2, "spatial.radius": r2},
               "first defaults": FIRST}
    times = {k: [] for k in configs}
    stages = {}
    for _ in range(repeats):
        for k, st in configs.items():
            r = restir.render(bench.scene("many-lights", res), restir.RenderConfig(
                method="restir-di", spp=1, frames=FRAMES, seed=1, width=res, height=res, settings=st))
            times[k].append(r.stats["ms_per_frame"])
            stages[k] = {n: v["total_ms"] / FRAMES for n, v in r.stats["stages"].items()}
    out = {}
    for k in configs:
        med = float(np.median(times[k]))
        out[k] = {"ms_per_frame_median": med, "ms_per_frame": times[k], "stages_ms_last": stages[k]}
        print(f"  {k:<30} {med:6.1f} ms/frame  (" + " ".join(f"{n} {v:.1f}" for n, v in stages[k].items()) + ")")
    bench.data["timing"] = out
    bench.save()


def phase_res512(bench):
    """512x512, seed 1: does the best radius in pixels grow with the image? (3 px, and the rule's
    15 and 30 px at 1080 lines, i.e. 7.1 and 14.2 px)."""
    res = 512
    table(bench, "many-lights", res, [1], [combo(5, f, 2, res, 32) for f in (3 / 512, 15 / 1080, 30 / 1080)],
          32, "res512")


def phase_long(bench, frames=64, res=128):
    """Per-frame relMSE over 64 frames (static, jittered camera): does the history drift?"""
    print(f"\n== long: many-lights {res}x{res}, 32 candidates, {frames} frames, seed 1 ==")
    ref, _ = bench.ref("many-lights", res)
    out = {}
    for label, st in (("no reuse", NO_REUSE),
                      ("T cap 2 only", {"temporal.cap": 2.0, "spatial.rounds": 0}),
                      ("T cap 5 only", {"temporal.cap": 5.0, "spatial.rounds": 0}),
                      ("T cap 20 only", {"temporal.cap": 20.0, "spatial.rounds": 0}),
                      ("T cap 2 + S 2x r 2 px", {"temporal.cap": 2.0, "spatial.radius": 2.0, "spatial.rounds": 2}),
                      ("T cap 5 + S 2x r 2 px", {"temporal.cap": 5.0, "spatial.radius": 2.0, "spatial.rounds": 2}),
                      ("T cap 20 + S 2x r 2 px", {"temporal.cap": 20.0, "spatial.radius": 2.0, "spatial.rounds": 2})):
        r = restir.render(bench.scene("many-lights", res), restir.RenderConfig(
            method="restir-di", spp=1, frames=frames, seed=1, width=res, height=res, keep_frames=True, settings=st))
        e = [relmse(f, ref) for f in r.frame_images.astype(np.float64)]
        out[label] = {"settings": st, "relmse_frames": e}
        print(f"  {label:<24} relMSE frames 8-15 {np.mean(e[8:16]):.4f}  16-31 {np.mean(e[16:32]):.4f}  "
              f"32-47 {np.mean(e[32:48]):.4f}  48-63 {np.mean(e[48:64]):.4f}", flush=True)
    bench.data["long"] = out
    bench.save()


def rule_radius(res, r1080, floor):
    return max(r1080 * res / 1080.0, floor)


def phase_proposal(bench, args):
    print(f"\n== proposal: radius = max({args.rule_r1080} * height / 1080, {args.rule_floor}) px, "
          f"temporal.cap {args.cap}, spatial.rounds {args.rounds}, 3 neighbours ==")
    out = {}
    for name in ("many-lights", "cornell-box"):
        for res in (64, 128, 256):
            seeds = [1, 2] if res <= 128 else [1]
            for cands in (32,) if res != 128 else (32, 8):
                prop = {"candidates": cands, "temporal.cap": float(args.cap), "spatial.rounds": args.rounds,
                        "spatial.radius": rule_radius(res, args.rule_r1080, args.rule_floor)}
                today = {"candidates": cands, **FIRST}
                rows = table(bench, name, res, seeds, [today, prop], cands, "proposal")
                out[f"{name}/{res}/{cands}"] = {"today": rows[0]["ratio"], "proposal": rows[1]["ratio"],
                                                "proposal_settings": prop, "relmse": rows[1]["relmse"],
                                                "relmse_no_reuse": rows[1]["relmse_no_reuse"],
                                                "ms_today": rows[0]["ms_per_frame"], "ms_prop": rows[1]["ms_per_frame"],
                                                "nonfinite": rows[1]["nonfinite"]}
    label = f"r1080={args.rule_r1080:g},floor={args.rule_floor:g},cap={args.cap:g},rounds={args.rounds}"
    bench.data.setdefault("proposals", {})[label] = {"rule_r1080": args.rule_r1080, "rule_floor": args.rule_floor,
                                                     "cap": args.cap, "rounds": args.rounds, "results": out}
    bench.save()
    print("\n  ratio no-reuse/config (same candidates): the first defaults -> proposal")
    for k, v in out.items():
        print(f"    {k:<24} {v['today']:5.2f}x -> {v['proposal']:5.2f}x   "
              f"(ms/frame {v['ms_today']:.1f} -> {v['ms_prop']:.1f})")


# The candidate rules of phase rules and rules_timing: (temporal.cap, spatial.rounds, radius in px
# as a function of the image height), 3 neighbours, 32 light + 1 BSDF candidates.
def rule_03a4532(h):
    """15 px up to 1080 lines, scaled with the height above (ReSTIR DI's auto radius at 03a4532)."""
    return 15.0 * max(1.0, h / 1080.0)


def rule_before(h):
    """max(2, 15 x height / 1080) px: ReSTIR DI's auto radius before 03a4532."""
    return max(2.0, 15.0 * h / 1080.0)


RULE_SCENES = ("many-lights", "cornell-box")
RULE_RADII = {64: [1.5, 2, 3, 5, 8, 15], 128: [2, 3, 5, 8, 15], 256: [2, 3, 5, 8, 15], 512: [3, 5, 8, 15]}
RULE_CAPS = {64: [2, 5], 128: [2, 5, 10], 256: [2, 5], 512: [5]}
RULE_SEEDS = {64: [1, 2], 128: [1, 2], 256: [1, 2], 512: [1]}


def phase_rules(bench, sizes=(128, 64, 256)):
    """Per-frame reuse gain (no reuse / config, same candidates and seed) of temporal.cap x radius
    in px x rounds at each size, on both scenes; raw and after Open Image Denoise. The radius grid
    holds the 03a4532 rule (15 px) and the rule before it (2 px at 64 and 128, 3.56 px at 256)."""
    out = bench.data.setdefault("rules", {})
    for res in sizes:
        radii = sorted(set(RULE_RADII[res]) | {rule_before(res)})
        for name in RULE_SCENES:
            seeds = RULE_SEEDS[res]
            configs = [{"candidates": 32, "temporal.cap": float(c), "spatial.rounds": r, "spatial.radius": float(x)}
                       for r in (1, 2) for c in RULE_CAPS[res] for x in radii]
            configs += [{"candidates": 32, "temporal.cap": float(c), "spatial.rounds": 0} for c in RULE_CAPS[res]]
            rows = table(bench, name, res, seeds, configs, 32, "rules")
            base = [bench.run(name, res, sd, {"candidates": 32, **NO_REUSE}) for sd in seeds]
            d0 = float(np.mean([b["relmse_denoised"] for b in base]))
            for row in rows:
                rs = [bench.run(name, res, sd, row["settings"]) for sd in seeds]
                row["relmse_denoised"] = float(np.mean([x["relmse_denoised"] for x in rs]))
                row["ratio_denoised"] = d0 / row["relmse_denoised"]
            out[f"{name}/{res}"] = rows
            print(f"  {name} {res}x{res}: gain raw / after the denoiser, by rounds and cap (rows), radius px (columns)")
            print("              " + " ".join(f"{x:>11g}" for x in radii))
            for r in (1, 2):
                for c in RULE_CAPS[res]:
                    cells = []
                    for x in radii:
                        row = next(w for w in rows if w["settings"].get("spatial.rounds") == r and
                                   w["settings"]["temporal.cap"] == c and w["settings"].get("spatial.radius") == x)
                        cells.append(f"{row['ratio']:5.2f}/{row['ratio_denoised']:5.2f}")
                    print(f"    {r} round{'s' if r > 1 else ' '} cap {c:>2g} " + " ".join(cells), flush=True)
            for row in rows:
                if row["settings"].get("spatial.rounds") == 0:
                    print(f"    temporal only, cap {row['settings']['temporal.cap']:g}: {row['ratio']:.2f} / "
                          f"{row['ratio_denoised']:.2f}")
    bench.save()


def candidate_rules(args, res):
    """{label: settings} of the rules compared by phases candidates and rules_timing: the 03a4532
    defaults, the rule before them, the proposal (--cap, --rounds, --rule-r1080, --rule-floor) and
    any --timing-rules."""
    rules = {"03a4532 (cap 5, 2 rounds, 15 px)": (5.0, 2, rule_03a4532(res)),
             "before 03a4532 (cap 5, 2 rounds, max(2, 15 h/1080) px)": (5.0, 2, rule_before(res)),
             "proposal": (float(args.cap), args.rounds, rule_radius(res, args.rule_r1080, args.rule_floor))}
    for spec in args.timing_rules:  # more rules: CAP,ROUNDS,R1080,FLOOR
        cap, rounds, r1080, floor = (float(x) for x in spec.split(","))
        rules[f"cap {cap:g}, {rounds:g} round(s), max({r1080:g} h/1080, {floor:g}) px"] = (
            cap, int(rounds), rule_radius(res, r1080, floor))
    return {k: {"temporal.cap": c, "spatial.rounds": r, "spatial.radius": float(x)} for k, (c, r, x) in rules.items()}


def phase_candidates(bench, args):
    """The candidate rules only (rows shared with phase rules where the settings agree), at
    --sizes on both scenes: per-frame reuse gain raw and after the denoiser."""
    out = bench.data.setdefault("candidates", {})
    for res in args.sizes:
        for name in RULE_SCENES:
            rules = candidate_rules(args, res)
            rows = table(bench, name, res, RULE_SEEDS[res], [{"candidates": 32, **st} for st in rules.values()], 32,
                         "rules")
            seeds = RULE_SEEDS[res]
            d0 = float(np.mean([bench.run(name, res, sd, {"candidates": 32, **NO_REUSE})["relmse_denoised"]
                                for sd in seeds]))
            for label, row in zip(rules, rows):
                row["rule"] = label
                row["relmse_denoised"] = float(np.mean([bench.run(name, res, sd, row["settings"])["relmse_denoised"]
                                                        for sd in seeds]))
                row["ratio_denoised"] = d0 / row["relmse_denoised"]
                print(f"    {name} {res}: {label:<58} gain {row['ratio']:.2f} raw, {row['ratio_denoised']:.2f} "
                      f"after the denoiser", flush=True)
            out[f"{name}/{res}"] = rows
    bench.save()


def phase_rules_timing(bench, args):
    """Frame time of the candidate rules as ratios to the 03a4532 defaults, taken in alternation
    (each repeat renders every configuration once, in turn), so that a busy machine slows both
    sides of a ratio alike; the median and range of the per-repeat ratios."""
    repeats = args.repeats
    print(f"\n== rules timing: many-lights, 32 candidates, {FRAMES} frames, {repeats} alternating repeats ==")
    out = {}
    for res in args.sizes:
        configs = {**candidate_rules(args, res), "no reuse": NO_REUSE}
        for label, st in configs.items():  # compile and warm up
            restir.render(bench.scene("many-lights", res), restir.RenderConfig(
                method="restir-di", spp=1, frames=2, seed=1, width=res, height=res, settings=st))
        times = {k: [] for k in configs}
        for _ in range(repeats):
            for label, st in configs.items():
                r = restir.render(bench.scene("many-lights", res), restir.RenderConfig(
                    method="restir-di", spp=1, frames=FRAMES, seed=1, width=res, height=res, settings=st))
                times[label].append(r.stats["ms_per_frame"])
        ref = np.array(times[next(iter(configs))])
        rows = {}
        for label, st in configs.items():
            ratio = np.array(times[label]) / ref
            rows[label] = {"settings": st, "ms_per_frame": times[label], "ratio_to_03a4532": ratio.tolist(),
                           "ratio_median": float(np.median(ratio))}
            print(f"  {res}x{res} {label:<56} {np.median(times[label]):6.1f} ms/frame (median), ratio "
                  f"{np.median(ratio):.3f} ({ratio.min():.3f}-{ratio.max():.3f})", flush=True)
        out[str(res)] = rows
    timing = bench.data.setdefault("rules_timing", {})  # by size: a run at other sizes keeps these
    for res, rows in out.items():
        timing[res] = {"proposal": {"rule_r1080": args.rule_r1080, "rule_floor": args.rule_floor, "cap": args.cap,
                                    "rounds": args.rounds}, "more_rules": args.timing_rules, "repeats": repeats,
                       "rows": rows}
    bench.save()


def phase_overflow(bench, frames=48, res=64):
    """cap 0 (no cap) with spatial reuse: the stored confidence M per frame, non-finite counters."""
    from restir.api import make_integrator

    print(f"\n== overflow: temporal.cap 0 (no cap), {res}x{res}, {frames} frames ==")
    scene = bench.scene("many-lights", res)
    out = {}
    for label, st in (("cap 0, S 2x r 3/128 h", {"temporal.cap": 0.0, "spatial.rounds": 2, "spatial.radius": 3 / 128 * res}),
                      ("cap 0, S 1x r 3/128 h", {"temporal.cap": 0.0, "spatial.rounds": 1, "spatial.radius": 3 / 128 * res}),
                      ("cap 0, S off", {"temporal.cap": 0.0, "spatial.rounds": 0}),
                      ("cap 20, S 2x r 3/128 h", {"temporal.cap": 20.0, "spatial.rounds": 2,
                                                  "spatial.radius": 3 / 128 * res})):
        cfg = restir.RenderConfig(method="restir-di", spp=1, frames=frames, seed=1, width=res, height=res, settings=st)
        integ = make_integrator(scene, cfg)
        rows = []
        first_bad = None
        for f in range(frames):
            img, _ = integ.render_frame(f)
            res_arr = integ.reservoirs.previous.numpy()  # this frame's final reservoirs
            M = res_arr["M"].astype(np.float64)
            nf = integ.counters.get("nonfinite_weights", 0) + integ.counters.get("nonfinite_outputs", 0)
            finite_M = M[np.isfinite(M)]
            rows.append({"frame": f, "M_max": float(finite_M.max()) if finite_M.size else float("nan"),
                         "M_median": float(np.median(finite_M)) if finite_M.size else float("nan"),
                         "M_nonfinite_pixels": int((~np.isfinite(M)).sum()), "nonfinite_counter": int(nf),
                         "image_nonfinite_pixels": int((~np.isfinite(img)).any(axis=2).sum())})
            if first_bad is None and (nf or rows[-1]["M_nonfinite_pixels"]):
                first_bad = f
        out[label] = {"settings": st, "frames": rows, "first_nonfinite_frame": first_bad}
        print(f"  {label}: first non-finite frame {first_bad}; M max at frames 0/8/16/24/32/40/47: " +
              " ".join(f"{rows[i]['M_max']:.3g}" for i in (0, 8, 16, 24, 32, 40, frames - 1)) +
              f"; non-finite counter at end {rows[-1]['nonfinite_counter']}, "
              f"non-finite image pixels at end {rows[-1]['image_nonfinite_pixels']}", flush=True)
    bench.data["overflow"] = out
    bench.save()


def phase_defaults(bench):
    """The shipped defaults against no reuse, both rendered by the code under test."""
    out = {}
    for name in ("many-lights", "cornell-box"):
        for res in (64, 128, 256):
            seeds = [1, 2] if res <= 128 else [1]
            rows = table(bench, name, res, seeds, [{"candidates": 32}], 32, "shipped defaults", fresh=True)
            out[f"{name}/{res}"] = rows[0]["ratio"]
    bench.data["defaults"] = out
    bench.save()
    print("\n  ratio no-reuse / shipped defaults: " + ", ".join(f"{k} {v:.2f}x" for k, v in out.items()))


def main():
    global OUT_DIR
    ap = argparse.ArgumentParser()
    ap.add_argument("--phase", nargs="+", default=["all"],
                    choices=["all", "main128", "res64", "res256", "small256", "cornell", "grey", "floor", "proposal",
                             "overflow", "timing", "res512", "long", "defaults", "rules", "rules512", "candidates",
                             "rules_timing"])
    ap.add_argument("--out", default=None, help="folder of the results JSON and the cached references")
    ap.add_argument("--json", default=None, help="results JSON (default: OUT/results.json)")
    ap.add_argument("--fresh", action="store_true", help="ignore cached rows in the JSON")
    ap.add_argument("--rule-r1080", type=float, default=15.0, help="proposal: radius in pixels at 1080 lines")
    ap.add_argument("--rule-floor", type=float, default=2.0, help="proposal: minimum radius in pixels")
    ap.add_argument("--cap", type=float, default=5.0, help="proposal: temporal.cap")
    ap.add_argument("--rounds", type=int, default=2, help="proposal: spatial.rounds")
    ap.add_argument("--sizes", type=int, nargs="+", default=[64, 128, 256], help="candidates: image sizes")
    ap.add_argument("--repeats", type=int, default=5, help="rules_timing: alternating repeats")
    ap.add_argument("--timing-rules", nargs="*", default=[], metavar="CAP,ROUNDS,R1080,FLOOR",
                    help="rules_timing: more rules beside the proposal")
    args = ap.parse_args()
    OUT_DIR = args.out or OUT_DIR
    args.json = args.json or os.path.join(OUT_DIR, "results.json")
    os.makedirs(OUT_DIR, exist_ok=True)
    bench = Bench(args.json, args.fresh)
    try:
        commit = subprocess.run(["git", "rev-parse", "HEAD"], cwd=os.path.dirname(restir.__file__),
                                capture_output=True, text=True).stdout.strip()
    except OSError:
        commit = ""
    bench.data["meta"] = {"restir_file": restir.__file__, "commit": commit, "frames": FRAMES,
                          "tail_frames": [TAIL.start, TAIL.stop - 1], "ref_spp": REF_SPP,
                          "relmse": "mean over pixels and channels of (x-ref)^2/(ref^2+0.01)",
                          "emitters": "hidden", "reference": "pt, strategy mis, max_depth 2, seed 99"}
    print(f"restir from {restir.__file__} (commit {commit[:10]})")
    # compile and warm up
    restir.render(bench.scene("many-lights", 64), restir.RenderConfig(method="restir-di", spp=1, frames=2, width=64,
                                                                       height=64))
    phases = args.phase
    if "all" in phases:
        phases = ["main128", "res64", "res256", "small256", "cornell", "grey", "floor", "proposal", "overflow", "timing", "res512",
                  "long"]
    t0 = time.perf_counter()
    for ph in phases:
        t = time.perf_counter()
        if ph == "proposal":
            phase_proposal(bench, args)
        elif ph == "rules_timing":
            phase_rules_timing(bench, args)
        elif ph == "candidates":
            phase_candidates(bench, args)
        elif ph == "rules512":
            phase_rules(bench, sizes=(512,))
        else:
            {"main128": phase_main128, "res64": phase_res64, "res256": phase_res256, "cornell": phase_cornell,
             "grey": phase_grey, "small256": phase_small256, "floor": phase_floor,
             "timing": phase_timing, "res512": phase_res512,
             "long": phase_long, "overflow": phase_overflow, "defaults": phase_defaults,
             "rules": phase_rules}[ph](bench)
        print(f"-- phase {ph}: {time.perf_counter() - t:.0f} s (total {time.perf_counter() - t0:.0f} s)", flush=True)
    print(f"\nresults: {args.json}")


if __name__ == "__main__":
    main()
