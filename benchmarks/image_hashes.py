"""Bit-for-bit image hashes of every method and its main settings: the check that a refactor
kept the images.

    .venv/bin/python benchmarks/image_hashes.py --out out/hashes-before.json
    ... refactor ...
    .venv/bin/python benchmarks/image_hashes.py --check out/hashes-before.json

Each case renders a small image on the CPU (Warp's tracer and Embree, 2 slices) and hashes the
float32 bytes of every frame and of the average, plus the counters. A hash only compares runs on
the same machine with the same Warp build; `--check` prints the cases that changed and exits 1.
"""
import argparse
import hashlib
import json
import os
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))
sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tests"))

import numpy as np  # noqa: E402

import restir  # noqa: E402

SHARED = os.environ.get("RESTIR_SCENES") or os.path.join(os.path.dirname(__file__), "..", "..", "shared", "scenes")


def scenes(tmp):
    from data.feature_scene import write_feature_scene

    write_feature_scene(tmp)
    return {
        "glossy": lambda: restir.load_scene("builtin:cornell-box-glossy", width=24, height=20),
        "room": lambda: restir.load_scene("builtin:indirect-room", width=24, height=20),
        "features": lambda: restir.load_scene(os.path.join(tmp, "scene.xml"), resx=24, resy=18),
        "bidir": lambda: restir.load_scene(os.path.join(SHARED, "veach-bidir", "scene.xml"), resx=24, resy=24),
    }


PT = [("pt", {}), ("pt", {"strategy": "nee"}), ("pt", {"strategy": "bsdf"}), ("pt", {"rr": True}),
      ("pt", {"nee.samples": 2})]
DI = [("restir-di", {}), ("restir-di", {"visibility": "shading", "candidates.bsdf": 0})]
RPT = [("restir-pt", {}), ("restir-pt", {"shift": "reconnection"}), ("restir-pt", {"shift": "replay"}),
       ("restir-pt", {"direct": "restir-di", "temporal.cap": 20.0}),
       ("restir-pt", {"candidates": 2, "spatial.rounds": 2}),
       ("restir-pt", {"spatial.reciprocal": True}), ("restir-pt", {"spatial.reciprocal": False})]
SR = [("suffix-restir", {}), ("suffix-restir", {"direct": "pt"}), ("suffix-restir", {"shift": "reconnection"})]
CASES = ([(s, m, st, None) for s in ("glossy", "room", "features", "bidir") for m, st in PT + RPT + SR]
         + [(s, m, st, 2) for s in ("glossy", "features") for m, st in DI]
         + [("glossy", "pt", {}, "orbit")])


def digest(a) -> str:
    return hashlib.sha256(np.ascontiguousarray(a, dtype=np.float32).tobytes()).hexdigest()[:16]


def run_case(load, method, settings, extra, tracer):
    kw = dict(method=method, spp=2, frames=3, seed=5, slices=2, tracer=tracer, keep_frames=True, settings=settings)
    if extra == "orbit":
        kw.update(camera_motion="orbit", camera_speed=2.0)
    elif extra is not None:
        kw["max_depth"] = extra
    res = restir.render(load(), restir.RenderConfig(**kw))
    return {"image": digest(res.image), "frames": [digest(f) for f in res.frame_images],
            "counters": res.stats.get("counters", {})}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", help="write the hashes here (JSON)")
    ap.add_argument("--check", help="compare against this file; exit 1 on any difference")
    ap.add_argument("--only", help="cases whose key contains this text")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        loaders = scenes(tmp)
        out = {}
        for tracer in ("warp", "embree"):
            for scene, method, settings, extra in CASES:
                key = f"{tracer} {scene} {method} {json.dumps(settings, sort_keys=True)} {extra or ''}".strip()
                if args.only and args.only not in key:
                    continue
                out[key] = run_case(loaders[scene], method, settings, extra, tracer)
                print(key, out[key]["image"], flush=True)
    if args.out:
        with open(args.out, "w") as f:
            json.dump(out, f, indent=1, sort_keys=True)
    if args.check:
        with open(args.check) as f:
            before = json.load(f)
        changed = [k for k in out if k in before and out[k] != before[k]]
        missing = [k for k in out if k not in before]
        for k in changed:
            print("CHANGED", k, before[k]["image"], "->", out[k]["image"])
        for k in missing:
            print("NEW (not in the baseline)", k)
        print(f"{len(out) - len(changed) - len(missing)} of {len(out)} cases bit-identical")
        sys.exit(1 if changed else 0)


if __name__ == "__main__":
    main()
