"""Suffix ReSTIR: the report's evaluation, reproduced and extended, each phase in one run.

    .venv/bin/python benchmarks/bench_suffix_restir.py --phase stages   # 800x800 shared Cornell box: per-stage ms, memory
    .venv/bin/python benchmarks/bench_suffix_restir.py --phase scaling  # final-gather time against N, M, radius
    .venv/bin/python benchmarks/bench_suffix_restir.py --phase grid     # the quality grid as one image, relMSE per tile
    .venv/bin/python benchmarks/bench_suffix_restir.py --phase quality  # equal-time relMSE vs pt and restir-pt
    .venv/bin/python benchmarks/bench_suffix_restir.py --phase search   # the three search structures' costs
    .venv/bin/python benchmarks/bench_suffix_restir.py --phase samples  # equal-sample relMSE: where the error is
    .venv/bin/python benchmarks/bench_suffix_restir.py --phase projection --frames 24  # the GPU case, from rays

stages: Suffix ReSTIR with its defaults for `--frames` frames after a warm-up frame, alternating
with the path tracer at 1 spp (A B A B), both twice; per-stage ms per frame grouped as the
report's six stages, the frame ratio, bytes per pixel by buffer. The search structure's cost is its
stage (boxes and build) plus its queries inside the gather, timed alone (one query per pixel per
gathered prefix, launched as the gather is).

scaling: the gather's ms per frame at `--size` for N in {1, 2, 4, 8} (M = 1), M in {1, 2, 4, 8}
(N = 4) and the search radius multiplier in {0.5, 1, 2, 4} (N = 4, M = 1), with the fraction of
gather slots the search filled.

grid: at `--size` on the Cornell box, 16 warm-up frames then one frame per tile: the path tracer
at 1, 8, 32, 128 spp; one prefix with 2, 8, 32, 128 suffixes; 1, 8, 32, 128 prefixes with one
suffix. Suffix ReSTIR gathers at most 8 suffixes and 16 prefixes per sample (the official
prototype's M <= 8), so a tile asking for more renders several samples per pixel (spp = count /
limit) and says so. relMSE against the path tracer at `--ref-spp` under each tile; written as one
EXR and PNG.

search: for each image side in `--search-sizes` and each structure (grid, hashgrid, bvh), the build
(the `search` stage's ms per frame over 2 frames) and the gather's queries timed alone, with the
candidates a query reads and the boxes that hold its point; the structures alternate within a size.

samples: at `--samples-size` on the indirect room, 24 frames of 1 sample per pixel each for the path
tracer, ReSTIR PT and Suffix ReSTIR in four configurations; relMSE per frame over frames 8..23
against the path tracer at 1024 spp, the share of it in the 10 worst pixels of each frame, and the
relMSE without them (is the error in a few fireflies or everywhere?).

projection: what a frame would buy if its cost were proportional to its rays (the assumption of
a GPU projection: a projection, not a measurement of a GPU). Per scene of `--projection-scenes`
at `--lines` lines: each method's rays per pixel per frame after its first frame (counted by the
renderer, frames 2-9), the path tracer's spp of the same rays (the integers on both sides of the
ratio), then `restir compare` at equal samples (`--frames` frames, the last `--frames` -
`--warmup` measured; OIDN per frame) with the path tracer at 1 spp and at those spp: each
method's denoised per-frame error against the path tracer's at the spp its rays would buy,
interpolated log-log between those integers (above 1: the method is lower). The CPU's
equal-time comparison is bench_error_structure.py's.

quality: 16 warm-up frames then 16 measured, relMSE per frame (frames 16..31) and accumulated,
against the path tracer at `--ref-spp`; the path tracer and ReSTIR PT get Suffix ReSTIR's measured
frame time (the path tracer by spp fitted as a + b spp; ReSTIR PT by spp as well).
"""
import argparse
import json
import math
import os
import sys
import time

import numpy as np

import restir

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))

REPORT_STAGES = {  # the report's six stages -> our stage names
    "1 prefix generation + temporal reuse": ("prefix",),
    "2 prefix spatial reuse": (),
    "3 suffix generation + temporal reuse": ("suffix",),
    "4 suffix spatial reuse": ("suffix_spatial",),
    "5 prefix search structure": ("search",),
    "6 final gather": ("gather",),
}
REPORT_MS = {"1 prefix generation + temporal reuse": 45.0, "3 suffix generation + temporal reuse": 72.0,
             "5 prefix search structure": 7.5, "6 final gather": 50.0}  # RTX 3070, 800x800 (the seed report)


from benchmarks.bench_restir_pt import relmse, render, shared  # noqa: E402  (after the path insert)


def query_ms(scene, size, max_depth, settings=None):
    """ms of the gather's search queries alone: per gathered prefix, one query per pixel at a fresh
    prefix end, launched over the pipeline's slices; the frame's structure, from a short render."""
    import warp as wp

    from restir.api import make_integrator
    from restir.device.rng import hash_combine, rng_key
    from restir.device.scene_device import SceneDevice
    from restir.integrators.common.gbuffer import GBuffer
    from restir.integrators.common.shading import load_shading
    from restir.integrators.suffix_restir.params import SRParams
    from restir.integrators.suffix_restir.prefix import trace_prefix
    from restir.integrators.suffix_restir.s2_search import (SEARCH_BVH, SEARCH_GRID, SearchStructure, grid_cell,
                                                         grid_slot, nearest_prefix_ends)
    from restir.parallel import launch_pixels

    @wp.kernel
    def ends_kernel(offset: int, scene: SceneDevice, params: SRParams, gb: GBuffer, points: wp.array(dtype=wp.vec3)):
        pixel = wp.tid() + offset
        points[pixel] = wp.vec3(1.0e30)
        sc = load_shading(scene, gb, pixel)
        if sc.valid != 0:
            pf = trace_prefix(scene, params, sc, hash_combine(rng_key(wp.uint32(3), wp.uint32(5), wp.uint32(7),
                                                                      wp.uint32(pixel)), wp.uint32(0)), False)
            if pf.valid != 0:
                points[pixel] = pf.hit.p

    @wp.kernel
    def queries_kernel(offset: int, search: SearchStructure, count: int, points: wp.array(dtype=wp.vec3),
                       found: wp.array(dtype=int)):
        pixel = wp.tid() + offset
        x = points[pixel]
        if x[0] < 1.0e29:
            found[pixel] = nearest_prefix_ends(search, x, count).found

    @wp.func
    def holds_box(c: wp.vec3, h: float, x: wp.vec3) -> int:
        d = c - x
        if wp.max(wp.abs(d[0]), wp.max(wp.abs(d[1]), wp.abs(d[2]))) <= h and wp.length_sq(d) < 3.0 * h * h:
            return 1
        return 0

    @wp.func
    def holds(search: SearchStructure, n: int, x: wp.vec3) -> int:
        """1 when box n holds x within its half-diagonal (search.consider's test), else 0."""
        return holds_box(search.centers[n], search.halves[n], x)

    @wp.func
    def cell_run(search: SearchStructure, lo: wp.vec3i, n: wp.vec3i, j: int) -> wp.vec2i:
        """The entries of cell j (x fastest) of the n[0] x n[1] x n[2] cells from lo: the cells the
        grid query reads (s2_search.grid_candidates), one by one."""
        c = wp.vec3i(lo[0] + j % n[0], lo[1] + (j // n[0]) % n[1], lo[2] + j // (n[0] * n[1]))
        return search.ranges[grid_slot(search, c)]

    @wp.kernel
    def count_kernel(offset: int, search: SearchStructure, points: wp.array(dtype=wp.vec3),
                     visited: wp.array(dtype=int), inside: wp.array(dtype=int)):
        """Per query: the candidates the structure hands over, and the boxes that hold the point."""
        pixel = wp.tid() + offset
        x = points[pixel]
        if x[0] < 1.0e29:
            n = int(0)
            v = int(0)
            k = int(0)
            if search.kind == SEARCH_GRID:
                lo = grid_cell(search, x - wp.vec3(search.radius))
                cells = grid_cell(search, x + wp.vec3(search.radius)) - lo + wp.vec3i(1)
                for j in range(cells[0] * cells[1] * cells[2]):  # the cells the query reads
                    run = cell_run(search, lo, cells, j)
                    v += run[1] - run[0]
                    for i in range(run[0], run[1]):
                        e = search.entries[i]
                        k += holds_box(wp.vec3(e[0], e[1], e[2]), e[3], x)
            elif search.kind == SEARCH_BVH:
                q = wp.bvh_query_aabb(search.id, x, x)
                while wp.bvh_query_next(q, n):
                    v += 1
                    k += holds(search, n, x)
            else:
                g = wp.hash_grid_query(search.id, x, search.radius)
                while wp.hash_grid_query_next(g, n):
                    v += 1
                    k += holds(search, n, x)
            visited[pixel] = v
            inside[pixel] = k

    sc = restir.load_scene(scene)
    sc.camera.width = sc.camera.height = size
    integ = make_integrator(sc, restir.RenderConfig(method="suffix-restir", spp=1, max_depth=max_depth,
                                                    settings=settings or {}))
    integ.render_frame(0)
    integ.render_frame(1)
    n = integ.num_pixels
    points = wp.zeros(n, dtype=wp.vec3, device=integ.device)
    found = wp.zeros(n, dtype=int, device=integ.device)
    launch_pixels(ends_kernel, n, [integ.dscene.scene, integ.params(1, 0), integ.gbuffers.previous], [points],
                  integ.device, integ.slices)
    args = [integ.search, int(integ.settings.gather_suffixes)]
    launch_pixels(queries_kernel, n, args, [points, found], integ.device, integ.slices)
    wp.synchronize()
    t = time.perf_counter()
    for _ in range(3):
        launch_pixels(queries_kernel, n, args, [points, found], integ.device, integ.slices)
    wp.synchronize()
    ms = (time.perf_counter() - t) / 3 * 1e3 * integ.settings.gather_prefixes
    visited = wp.zeros(n, dtype=int, device=integ.device)
    inside = wp.zeros(n, dtype=int, device=integ.device)
    launch_pixels(count_kernel, n, [integ.search, points], [visited, inside], integ.device, integ.slices)
    valid = points.numpy()[:, 0] < 1.0e29
    query_ms.counts = (float(visited.numpy()[valid].mean()), float(inside.numpy()[valid].mean()))
    return ms


def phase_stages(args, out):
    scene = restir.load_scene(shared("cornell-box"))
    common = dict(max_depth=args.max_depth, width=args.stage_size, height=args.stage_size)
    render(scene, "suffix-restir", 1, **common)  # compile, warm up
    render(scene, "pt", 1, **common)
    ms = []
    for rep in range(2):
        a = render(scene, "suffix-restir", args.frames, seed=rep, **common)
        b = render(scene, "pt", args.frames, seed=rep, **common)
        ms.append((a.stats["ms_per_frame"], b.stats["ms_per_frame"]))
    stages = {k: v["total_ms"] / args.frames for k, v in a.stats["stages"].items()}
    grouped = {k: sum(stages.get(s, 0.0) for s in v) for k, v in REPORT_STAGES.items()}
    q = query_ms(shared("cornell-box"), args.stage_size, args.max_depth)
    bpp = a.stats["bytes_per_pixel"]
    print(f"\ncornell-box {args.stage_size}x{args.stage_size} max_depth {args.max_depth}: Suffix ReSTIR ms per frame")
    print("  " + "  ".join(f"{k} {v:.0f}" for k, v in stages.items()))
    for k, v in grouped.items():
        print(f"  report stage {k}: {v:.0f} ms" + (f" (report: {REPORT_MS[k]} ms on an RTX 3070)" if k in REPORT_MS else ""))
    print(f"  search structure: build {stages.get('search', 0):.1f} ms + queries {q:.1f} ms = "
          f"{100 * (stages.get('search', 0) + q) / ms[-1][0]:.1f}% of the frame")
    print(f"  frame {ms[-1][0]:.0f} ms, path tracer 1 spp {ms[-1][1]:.0f} ms; ratio "
          + ", ".join(f"{x / y:.2f}" for x, y in ms))
    print(f"  bytes per pixel: {bpp['total']:.0f}; " + ", ".join(f"{k} {v:.0f}" for k, v in bpp.items() if k != "total"))
    print(f"  shifts {json.dumps(a.stats['shifts'])}; gather slots {a.stats['gather_slots']}")
    # rays per pixel and frame: the work each stage does, whatever the machine
    px = args.stage_size ** 2 * args.frames
    rays = {k: v / px for k, v in a.stats["rays_by_stage"].items() if v}
    pt_rays = b.stats["rays"] / px
    print("  rays per pixel per frame: " + ", ".join(f"{k} {v:.2f}" for k, v in rays.items())
          + f"; total {sum(rays.values()):.2f}, the path tracer {pt_rays:.2f} (ratio {sum(rays.values()) / pt_rays:.2f})")
    out["stages"] = {"stages_ms": stages, "report_stages_ms": grouped, "search_query_ms": q, "frame_ms": ms,
                     "bytes_per_pixel": bpp, "shifts": a.stats["shifts"], "gather_slots": a.stats["gather_slots"],
                     "rays_per_pixel": rays, "pt_rays_per_pixel": pt_rays}


def phase_scaling(args, out):
    scene = restir.load_scene(shared("cornell-box"))
    common = dict(max_depth=args.max_depth, width=args.size, height=args.size)
    render(scene, "suffix-restir", 1, **common)
    rows = {}
    grid = [("N", {"gather.prefixes": n}) for n in (1, 2, 4, 8)] + \
           [("M", {"gather.suffixes": m}) for m in (1, 2, 4, 8)] + \
           [("radius", {"gather.radius": r}) for r in (0.5, 1.0, 2.0, 4.0)]
    for name, st in grid:
        a = render(scene, "suffix-restir", args.frames, settings=st, **common)
        g = a.stats["stages"]["gather"]["total_ms"] / args.frames
        key = f"{name} {list(st.values())[0]}"
        rows[key] = {"gather_ms": g, "frame_ms": a.stats["ms_per_frame"], "slots": a.stats["gather_slots"]}
        print(f"  {key}: gather {g:.0f} ms, frame {a.stats['ms_per_frame']:.0f} ms, slots {a.stats['gather_slots']}")
    out["scaling"] = rows


def labelled_png(path, image, tile, labels):
    """The grid as an sRGB PNG with each tile's label under it (Pillow's default font)."""
    from PIL import Image, ImageDraw

    from restir.image_io import linear_to_srgb

    rgb = (np.clip(linear_to_srgb(np.clip(image, 0, None)), 0, 1) * 255 + 0.5).astype(np.uint8)
    rows, cols = image.shape[0] // tile, image.shape[1] // tile
    band = 28
    canvas = Image.new("RGB", (image.shape[1], rows * (tile + band)), "white")
    draw = ImageDraw.Draw(canvas)
    for r in range(rows):
        canvas.paste(Image.fromarray(rgb[r * tile:(r + 1) * tile]), (0, r * (tile + band)))
        for c in range(cols):
            draw.text((c * tile + 2, r * (tile + band) + tile + 1), labels[r * cols + c], fill="black")
    canvas.save(path)


def phase_grid(args, out):
    from restir.image_io import write_image

    scene = restir.load_scene(shared("cornell-box"))
    common = dict(max_depth=args.max_depth, width=args.size, height=args.size, keep_frames=True)
    ref = render(scene, "pt", 1, seed=99, spp=args.ref_spp, **common).image.astype(np.float64)
    tiles, labels = [], []
    for n in (1, 8, 32, 128):
        img = render(scene, "pt", 1, spp=n, **common).image
        tiles.append(img)
        labels.append(f"path tracer {n} spp")
    for kind, counts in (("suffixes", (2, 8, 32, 128)), ("prefixes", (1, 8, 32, 128))):
        limit = 8 if kind == "suffixes" else 16
        for c in counts:
            spp = max(1, c // limit)
            st = {"gather.prefixes": 1, "gather.suffixes": min(c, limit)} if kind == "suffixes" else \
                {"gather.prefixes": min(c, limit), "gather.suffixes": 1}
            r = render(scene, "suffix-restir", 17, spp=spp, settings=st, **common)
            tiles.append(r.frame_images[-1])
            what = f"1 prefix x {c} suffixes" if kind == "suffixes" else f"{c} prefixes x 1 suffix"
            labels.append(what + (f" ({spp} spp of {min(c, limit)})" if spp > 1 else ""))
    errs = [relmse(t.astype(np.float64), ref) for t in tiles]
    rows = [np.concatenate(tiles[i:i + 4], axis=1) for i in range(0, 12, 4)]
    image = np.concatenate(rows, axis=0).astype(np.float32)
    os.makedirs(args.out_dir, exist_ok=True)
    write_image(os.path.join(args.out_dir, "suffix_grid.exr"), image)
    labelled_png(os.path.join(args.out_dir, "suffix_grid.png"), image, args.size,
                 [f"{l}\nrelMSE {e:.4f}" for l, e in zip(labels, errs)])
    for l, e in zip(labels, errs):
        print(f"  {l}: relMSE {e:.4f}")
    out["grid"] = dict(zip(labels, errs))


def phase_quality(args, out):
    from benchmarks.bench_restir_pt import EqualTime, MEAS, WARM

    scenes = {"indirect-room": "builtin:indirect-room", "veach-bidir": shared("veach-bidir")}
    for name, spec in scenes.items():
        et = EqualTime(args, spec)
        render(et.scene, "suffix-restir", 1, **et.common)  # compile, warm up
        a = render(et.scene, "suffix-restir", WARM + MEAS, **et.common)
        target = a.stats["ms_per_frame"]
        spp = max(1, int(round((target - et.fixed) / et.slope)))
        b = render(et.scene, "pt", WARM + MEAS, spp=spp, **et.common)
        # ReSTIR PT's frame time at 1 spp, and spp fitted to Suffix ReSTIR's time
        c1 = render(et.scene, "restir-pt", 4, **et.common).stats["ms_per_frame"]
        pt_spp = max(1, int(round(target / c1)))
        c = render(et.scene, "restir-pt", WARM + MEAS, spp=pt_spp, **et.common)
        res = {}
        for label, r in (("suffix-restir", a), ("pt", b), ("restir-pt", c)):
            f = r.frame_images[WARM:].astype(np.float64)
            res[label] = {"ms": r.stats["ms_per_frame"], "relmse_frame": float(np.mean([relmse(x, et.ref) for x in f])),
                          "relmse_accumulated": relmse(f.mean(0), et.ref)}
        print(f"\n{name} {args.size}x{args.size}: Suffix ReSTIR {target:.0f} ms; path tracer {spp} spp "
              f"({b.stats['ms_per_frame']:.0f} ms); ReSTIR PT {pt_spp} spp ({c.stats['ms_per_frame']:.0f} ms)")
        for label, v in res.items():
            print(f"  {label}: relMSE per frame {v['relmse_frame']:.4f}, accumulated {v['relmse_accumulated']:.4f}")
        out[f"quality {name}"] = res


def phase_search(args, out):
    scene = shared("cornell-box")
    rows = {}
    for size in args.search_sizes:
        for kind in ("grid", "hashgrid", "bvh"):
            settings = {"gather.search": kind}
            build = render(restir.load_scene(scene), "suffix-restir", 2, width=size, height=size,
                           max_depth=args.max_depth, settings=settings).stats["stages"]["search"]["total_ms"] / 2
            q = query_ms(scene, size, args.max_depth, settings)
            n = 4 * size * size  # queries: one per pixel per gathered prefix (N = 4)
            rows[f"{size} {kind}"] = {"build_ms": build, "query_ms": q, "us_per_query": 1e3 * q / n,
                                      "candidates": query_ms.counts[0], "holding": query_ms.counts[1]}
            print(f"  {size}x{size} {kind}: build {build:.1f} ms, queries {q:.0f} ms ({1e3 * q / n:.2f} us each), "
                  f"{query_ms.counts[0]:.1f} candidates read, {query_ms.counts[1]:.1f} hold the point", flush=True)
    out["search"] = rows


def phase_samples(args, out):
    scene = restir.load_scene("builtin:indirect-room")
    common = dict(max_depth=args.max_depth, keep_frames=True, width=args.samples_size, height=args.samples_size)
    ref = render(scene, "pt", 1, seed=99, spp=1024, **common).image.astype(np.float64)
    no_reuse = {"prefix.temporal": False, "suffix.temporal": False, "suffix.spatial.rounds": 0}
    rows = {}
    for label, method, settings in [("pt", "pt", {}), ("restir-pt", "restir-pt", {}),
                                    ("suffix-restir", "suffix-restir", {}),
                                    ("suffix-restir, gather only", "suffix-restir", no_reuse),
                                    ("suffix-restir, N = 1", "suffix-restir", {"gather.prefixes": 1}),
                                    ("suffix-restir, canonical per prefix", "suffix-restir",
                                     {"gather.canonical_per_prefix": True})]:
        f = render(scene, method, 24, settings=settings, **common).frame_images[8:].astype(np.float64)
        err = np.array([((x - ref) ** 2 / (ref ** 2 + 0.01)).mean(-1).ravel() for x in f])  # frames x pixels
        worst = -np.sort(-err, axis=1)
        rows[label] = {"relmse_frame": float(err.mean()),
                       "worst10_share": float((worst[:, :10].sum(1) / worst.sum(1)).mean()),
                       "relmse_without_worst10": float(worst[:, 10:].sum(1).mean() / err.shape[1])}
        print(f"  {label}: relMSE per frame {rows[label]['relmse_frame']:.4f}, the 10 worst pixels "
              f"{rows[label]['worst10_share']:.2f} of it, without them {rows[label]['relmse_without_worst10']:.4f}",
              flush=True)
    out["samples"] = rows


def rays_per_frame(scene, method, width, height, max_depth, seed=1):
    """Rays per pixel per frame after the first frame (which traces the emission rays at every
    pixel and starts without history): frames 2-9 of one render."""
    def count(frames):
        return restir.render(scene, restir.RenderConfig(method=method, spp=1, frames=frames, seed=seed, width=width,
                                                        height=height, max_depth=max_depth)).stats["rays"]
    return (count(9) - count(1)) / (8 * width * height)


def phase_projection(args, out):
    from benchmarks.bench_error_structure import SCENES, load
    from restir.compare import compare
    from restir.compare.headline import at_spp

    rows = []
    for name, spec, aspect, _, depth in SCENES:
        if name not in args.projection_scenes:
            continue
        scene = load(spec)
        h = args.lines
        w = int(round(h * aspect / 2)) * 2
        rays = {m: rays_per_frame(scene, m, w, h, depth) for m in ("pt", "restir-pt", "suffix-restir")}
        ratio = {m: rays[m] / rays["pt"] for m in ("restir-pt", "suffix-restir")}
        # the path tracer at the spp on both sides of each ratio; its error between them interpolated
        # log-log (the error of n independent samples falls as a power of n)
        spp = {m: sorted({max(1, math.floor(v)), max(1, math.ceil(v))}) for m, v in ratio.items()}
        pts = sorted({k for v in spp.values() for k in v} | {1})
        methods = [f"pt:spp={k}" if k > 1 else "pt" for k in pts] + ["restir-pt", "suffix-restir"]
        r = compare(scene, methods, frames=args.frames, warmup=args.warmup, width=w, height=h, max_depth=depth,
                    reference_spp=args.ref_spp, denoise=True, correlation_runs=0, seed=args.seed)
        by = {m.label: m.metrics for m in r.methods}
        pt_results = {m.spp: m for m in r.methods if m.method == "pt"}

        def pt_at(k, key):
            return pt_results[k].metrics[key]

        def pt_between(m, key):  # restir compare's own interpolation (headline.at_spp)
            return at_spp(pt_results[spp[m][0]], pt_results[spp[m][-1]], ratio[m], key)

        print(f"\n## {name} ({w}x{h}), rays per pixel per frame: " + ", ".join(f"{m} {v:.2f}" for m, v in rays.items()))
        print("| scene | method | rays / pt's | raw | denoised | " + " | ".join(f"pt {k} spp, denoised" for k in pts)
              + " | pt at the ratio (log-log) | pt / method | F(8) |")
        for m in ("restir-pt", "suffix-restir"):
            x = by[m]
            base = pt_between(m, "relmse_denoised_frame")
            row = {"scene": name, "method": m, "rays": rays[m], "pt_rays": rays["pt"], "ratio": ratio[m],
                   "ms_per_frame": x["ms_per_frame"], "relmse_frame": x["relmse_frame"],
                   "denoised": x["relmse_denoised_frame"],
                   "pt_denoised": {k: pt_at(k, "relmse_denoised_frame") for k in pts},
                   "pt_raw": {k: pt_at(k, "relmse_frame") for k in pts},
                   "pt_denoised_at_ratio": base, "f8": x["correlation_factor"]["8"]}
            rows.append(row)
            print(f"| {name} | {m} | {ratio[m]:.2f} | {x['relmse_frame']:.3g} | {x['relmse_denoised_frame']:.3g} | "
                  + " | ".join(f"{pt_at(k, 'relmse_denoised_frame'):.3g}" for k in pts)
                  + f" | {base:.3g} | {base / x['relmse_denoised_frame']:.2f} | {x['correlation_factor']['8']:.2f} |",
                  flush=True)
    out["projection"] = rows


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--phase", choices=["stages", "scaling", "grid", "quality", "search", "samples", "projection", "all"], default="all")
    ap.add_argument("--frames", type=int, default=3)
    ap.add_argument("--max-depth", type=int, default=8)
    ap.add_argument("--stage-size", type=int, default=800)
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--ref-spp", type=int, default=2048)
    ap.add_argument("--out-dir", default="out/bench_suffix")
    ap.add_argument("--samples-size", type=int, default=96)
    ap.add_argument("--search-sizes", type=int, nargs="+", default=[256, 512, 800])
    ap.add_argument("--projection-scenes", nargs="+", default=["indirect-room", "cornell-box-glossy", "veach-ajar"])
    ap.add_argument("--lines", type=int, default=128, help="projection: image height")
    ap.add_argument("--warmup", type=int, default=8, help="projection: frames before the error is measured")
    ap.add_argument("--seed", type=int, default=1, help="projection: the methods' seed")
    ap.add_argument("--json")
    args = ap.parse_args()
    out = {}
    for phase in ("stages", "scaling", "grid", "quality", "search", "samples", "projection"):
        if args.phase in (phase, "all"):
            globals()[f"phase_{phase}"](args, out)
    if args.json:
        with open(args.json, "w") as f:
            json.dump(out, f, indent=2)


if __name__ == "__main__":
    main()
