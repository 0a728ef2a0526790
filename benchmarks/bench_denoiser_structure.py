"""What a denoiser keeps of an error: each method's frames through Open Image Denoise, and the same
errors rearranged before the denoiser.

For frames 8-15 of a 16-frame render at 128x128 (a still camera), against the path tracer at
1024 spp:

- `--phase shuffle`: the relative error (frame - reference) / reference of each frame shuffled
  within 2x2, 4x4 and 8x8 blocks (block means kept: F(8) kept, finer structure gone) and over the
  whole image, put back on the reference and denoised. Where rearranging lowers the denoised
  error at an unchanged raw error, the denoiser kept the error's arrangement: structure at that
  scale. (Only the 2x2 shuffle keeps the raw error close: shuffled over larger blocks, a large
  relative error of a dark pixel lands on a bright one.)
- `--phase regions`: each method's error split by region: the band of pixels that see an emitter
  directly (the emission seen directly, max_depth 1 at 256 spp, non-zero, widened by one pixel),
  the geometric edges and the interior; and outside the band into the channels' mean and the
  colour (each channel's deviation from the mean). With the path tracer at 1-4 spp for the
  equal-time reading. Inside the band the error is the primary rays' anti-aliasing, which path
  reuse cannot lower and which the path tracer samples once per spp; and rows with
  `emission.rays` (that term from more camera rays). `--rows LABEL ...` runs only those rows.
- `--phase jitter`: the same methods with the camera's filter offset on and off (pixel-centre
  rays, `RenderConfig.jitter`), each against its own reference; with the lag-1 correlation of
  horizontally neighbouring pixels' errors and F(8).

    .venv/bin/python benchmarks/bench_denoiser_structure.py --phase shuffle
    .venv/bin/python benchmarks/bench_denoiser_structure.py --phase jitter
    .venv/bin/python benchmarks/bench_denoiser_structure.py --phase regions --scene builtin:cornell-box-glossy

(What it showed: docs/guide/when_restir_pays.md#what-the-denoiser-keeps-correlated-error and
docs/guide/when_restir_pays.md#the-emission-rays.)
"""
import argparse
import json
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))

import numpy as np  # noqa: E402

import restir  # noqa: E402
from restir.compare.denoise import Denoiser  # noqa: E402
from restir.compare.metrics import relmse  # noqa: E402
from restir.compare.reference import path_traced_reference  # noqa: E402
from restir.compare.structure import correlation_factor  # noqa: E402
from restir.config import RenderConfig  # noqa: E402

SIZE = 128
FRAMES, WARMUP = 16, 8
METHODS = [("pt 1 spp", "pt", 1, {}), ("pt 2 spp", "pt", 2, {}),
           ("restir-pt, temporal only", "restir-pt", 1, {"spatial.rounds": 0}), ("restir-pt", "restir-pt", 1, {})]


def relative_error(frame, ref):
    """e / sqrt(ref^2 + 0.01): the error relMSE averages the square of."""
    return ((frame - ref) / np.sqrt(ref ** 2 + 0.01)).mean(-1)


def shuffled(frame, ref, block, rng):
    """The frame with its relative error (frame / ref - 1) shuffled within block x block tiles
    (block 0: over the whole image), on the reference: non-negative, since frame >= 0. Pixels
    with a black reference keep their own error."""
    dark = ref <= 1e-6
    r = np.where(dark, 0.0, (frame - ref) / np.where(dark, 1.0, ref))
    h, w, _ = r.shape
    out = np.empty_like(r)
    if block == 0:
        out = r.reshape(-1, 3)[rng.permutation(h * w)].reshape(h, w, 3)
    else:
        for y in range(0, h, block):
            for x in range(0, w, block):
                t = r[y:y + block, x:x + block]
                flat = t.reshape(-1, 3)
                out[y:y + block, x:x + block] = flat[rng.permutation(len(flat))].reshape(t.shape)
    return np.where(dark, frame, ref * (1.0 + out))


def frames_of(scene, method, spp, settings, jitter, seed):
    res = restir.render(scene, RenderConfig(method=method, spp=spp, frames=FRAMES, width=SIZE, height=SIZE,
                                            keep_frames=True, seed=seed, settings=settings, jitter=jitter))
    return np.asarray(res.frame_images, np.float64)[WARMUP:], res.stats["ms_per_frame"]


def phase_shuffle(scene, seed, out):
    base = RenderConfig(method="pt", spp=1, frames=1, width=SIZE, height=SIZE)
    ref = path_traced_reference(scene, 1024, base).image
    den = Denoiser.for_scene(scene, base)
    rng = np.random.default_rng(5)
    rows = {}
    for label, method, spp, settings in METHODS:
        frames, ms = frames_of(scene, method, spp, settings, True, seed)
        m = {"ms": ms, "raw": [], "denoised": [], "lag1": []}
        for f in frames:
            e = relative_error(f, ref)
            m["raw"].append(relmse(f, ref))
            m["denoised"].append(relmse(den(f), ref))
            m["lag1"].append(float(np.mean(e[:, 1:] * e[:, :-1]) / np.mean(e * e)))
            for b in (2, 4, 8, 0):
                g = shuffled(f, ref, b, rng)
                m.setdefault(f"raw_{b}", []).append(relmse(g, ref))
                m.setdefault(f"denoised_{b}", []).append(relmse(den(g), ref))
        rows[label] = {k: (float(np.mean(v)) if isinstance(v, list) else v) for k, v in m.items()}
        r = rows[label]
        print(f"{label:26s} raw {r['raw']:.3f} denoised {r['denoised']:.4f} lag-1 {r['lag1']:.3f} | shuffled, raw and "
              f"denoised: 2x2 {r['raw_2']:.3f} {r['denoised_2']:.4f}, 4x4 {r['raw_4']:.3f} {r['denoised_4']:.4f}, "
              f"8x8 {r['raw_8']:.3f} {r['denoised_8']:.4f}, whole image {r['raw_0']:.3f} {r['denoised_0']:.4f}",
              flush=True)
    out["shuffle"] = rows


REGION_METHODS = [("pt 1 spp", "pt", 1, {}), ("pt 2 spp", "pt", 2, {}), ("pt 3 spp", "pt", 3, {}),
                  ("pt 4 spp", "pt", 4, {}), ("restir-pt, temporal only", "restir-pt", 1, {"spatial.rounds": 0}),
                  ("restir-pt", "restir-pt", 1, {}),
                  ("restir-pt, shade.expected", "restir-pt", 1, {"shade.expected": True}),
                  ("restir-pt, shade.expected, direct=nee", "restir-pt", 1, {"shade.expected": True, "direct": "nee"}),
                  ("pt 8 spp", "pt", 8, {}), ("suffix-restir", "suffix-restir", 1, {}),
                  # the emission seen directly from more camera rays (common/primary_hits.py)
                  ("pt 2 spp, emission.rays=2", "pt", 2, {"emission.rays": 2}),
                  ("restir-pt, emission.rays=2", "restir-pt", 1, {"emission.rays": 2}),
                  ("restir-pt, emission.rays=4", "restir-pt", 1, {"emission.rays": 4}),
                  ("restir-pt, temporal only, emission.rays=4", "restir-pt", 1,
                   {"spatial.rounds": 0, "emission.rays": 4}),
                  ("restir-pt, emission.rays=4, shade.expected, direct=nee", "restir-pt", 1,
                   {"emission.rays": 4, "shade.expected": True, "direct": "nee"}),
                  ("suffix-restir, emission.rays=8", "suffix-restir", 1, {"emission.rays": 8})]


def phase_regions(scene, seed, out, rows_wanted=None):
    """The error per region: the band of pixels that see an emitter, the geometric edges (where
    the noise-free guides change between neighbours, widened by a pixel) and the interior; and the
    error outside the band split into its mean over the channels (what the luminance carries) and
    the channels' deviations from that mean (the colour's share)."""
    from scipy.ndimage import binary_dilation

    base = RenderConfig(method="pt", spp=1, frames=1, width=SIZE, height=SIZE)
    ref = path_traced_reference(scene, 1024, base).image
    seen = restir.render(scene, RenderConfig(method="pt", spp=256, frames=1, width=SIZE, height=SIZE, max_depth=1,
                                             seed=7)).image
    band = binary_dilation(seen.max(-1) > 0.0, iterations=1)
    den = Denoiser.for_scene(scene, base)
    g = np.concatenate([den.albedo, den.normal], -1)
    step = np.zeros(g.shape[:2])
    step[:, 1:] = np.abs(g[:, 1:] - g[:, :-1]).max(-1)
    step[1:] = np.maximum(step[1:], np.abs(g[1:] - g[:-1]).max(-1))
    edges = binary_dilation(step > 0.05, iterations=1) & ~band
    interior = ~band & ~edges
    rest = ~band
    scale = 1.0 / np.sqrt(ref ** 2 + 0.01)  # relMSE's weight is its square
    rows = {"pixels": {"band": int(band.sum()), "edges": int(edges.sum()), "interior": int(interior.sum())}}
    for label, method, spp, settings in REGION_METHODS:
        if rows_wanted and label not in rows_wanted:
            continue
        frames, ms = frames_of(scene, method, spp, settings, True, seed)
        r = {"ms": ms}
        for kind, fs in (("raw", frames), ("denoised", [den(f) for f in frames])):
            e = np.stack([(f - ref) * scale for f in fs])     # (frames, H, W, 3)
            sq = (e ** 2).mean(-1).mean(0)                     # per pixel
            r[kind] = float(sq.mean())
            for name, mask in (("band", band), ("edges", edges), ("interior", interior)):
                r[f"{kind}_{name}"] = float(sq[mask].sum() / sq.size)
            er = e[:, rest]
            mean = er.mean(-1, keepdims=True)
            r[f"{kind}_rest_mean"] = float((mean[..., 0] ** 2).sum() / (len(fs) * sq.size))
            r[f"{kind}_rest_colour"] = float(((er - mean) ** 2).mean(-1).sum() / (len(fs) * sq.size))
        rows[label] = r
        print(f"{label:38s} {ms:4.0f} ms | denoised {r['denoised']:.5f}: band {r['denoised_band']:.5f} edges "
              f"{r['denoised_edges']:.5f} interior {r['denoised_interior']:.5f}; outside the band mean "
              f"{r['denoised_rest_mean']:.5f} colour {r['denoised_rest_colour']:.5f} | raw {r['raw']:.4f}: outside "
              f"the band mean {r['raw_rest_mean']:.4f} colour {r['raw_rest_colour']:.4f}", flush=True)
    out["regions"] = rows


def phase_jitter(scene, seed, out):
    rows = {}
    for jitter in (True, False):
        base = RenderConfig(method="pt", spp=1, frames=1, width=SIZE, height=SIZE, jitter=jitter)
        ref = path_traced_reference(scene, 1024, base).image
        den = Denoiser.for_scene(scene, base)
        for label, method, spp, settings in METHODS:
            frames, ms = frames_of(scene, method, spp, settings, jitter, seed)
            es = [relative_error(f, ref) for f in frames]
            r = {"ms": ms, "raw": float(np.mean([relmse(f, ref) for f in frames])),
                 "denoised": float(np.mean([relmse(den(f), ref) for f in frames])),
                 "lag1": float(np.mean([np.mean(e[:, 1:] * e[:, :-1]) / np.mean(e * e) for e in es])),
                 "F8": float(np.mean([correlation_factor((f - ref) / np.sqrt(ref ** 2 + 0.01), 8) for f in frames]))}
            rows[f"jitter={jitter} {label}"] = r
            print(f"jitter {str(jitter):5s} {label:26s} {ms:.0f} ms/frame raw {r['raw']:.3f} denoised {r['denoised']:.4f} "
                  f"lag-1 {r['lag1']:.3f} F(8) {r['F8']:.2f}", flush=True)
    out["jitter"] = rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--phase", choices=("shuffle", "jitter", "regions"), required=True)
    ap.add_argument("--scene", default="builtin:indirect-room")
    ap.add_argument("--seed", type=int, default=3)
    ap.add_argument("--json", help="write the rows here")
    ap.add_argument("--rows", nargs="*", help="regions: only these rows (their labels, as printed)")
    args = ap.parse_args()
    scene = restir.load_scene(args.scene)
    out = {"scene": args.scene, "seed": args.seed}
    if args.phase == "regions":
        phase_regions(scene, args.seed, out, args.rows)
    else:
        {"shuffle": phase_shuffle, "jitter": phase_jitter}[args.phase](scene, args.seed, out)
    if args.json:
        os.makedirs(os.path.dirname(os.path.abspath(args.json)), exist_ok=True)
        with open(args.json, "w") as f:
            json.dump(out, f, indent=1)


if __name__ == "__main__":
    main()
