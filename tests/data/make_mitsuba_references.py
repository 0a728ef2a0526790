"""Render the Mitsuba 3 references of the shared scenes used by tests/integration/test_mitsuba.py.

    pip install mitsuba==3.9.1            # and Debian's libllvm19 for the llvm_ad_rgb variant
    DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so \\
        python tests/data/make_mitsuba_references.py [--scenes cornell-box ...]

For each scene: K renders with independent seeds at the resolution, spp and max_depth below;
stores the mean (`NAME.mean.exr`) and the variance of that mean (`NAME.var.exr`, from the
spread of the K renders) plus `NAME.json` with the exact settings and this command.
"""
import argparse
import json
import os
import platform
import re
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
SHARED = os.path.normpath(os.path.join(HERE, "..", "..", "..", "shared", "scenes"))
sys.path.insert(0, os.path.normpath(os.path.join(HERE, "..", "..")))

# name: (resx, resy, max_depth, spp per render, renders K)
REFERENCES = {
    "cornell-box": (48, 48, 8, 4096, 16),
    "veach-mis": (64, 36, 3, 4096, 16),
    "veach-bidir": (48, 48, 7, 8192, 16),
    "features": (48, 36, 5, 4096, 16),  # tests/data/feature_scene.py: envmap, texture, plastic, ...
    "textures": (48, 36, 5, 4096, 16),  # tests/data/feature_scene.py: checkerboard, filter / wrap modes, to_uv
    "bumps": (48, 36, 5, 4096, 16),  # tests/data/feature_scene.py: bumpmap around six BSDFs, scale, to_uv, switches
    "normalmaps": (48, 36, 5, 4096, 16),  # tests/data/feature_scene.py: normalmap around five BSDFs, switches, mirrored uvs
    "masks": (48, 36, 5, 4096, 16),  # tests/data/feature_scene.py: mask by texture (luminance) and constant, around bumpmap, conductors
    "delta-lights": (48, 36, 5, 4096, 16),  # tests/data/feature_scene.py: point, spot, directional, area light, constant env
    "thinlens": (48, 36, 5, 4096, 16),  # tests/data/feature_scene.py: the same room through a thin lens
    "delta-lights-direct": (48, 36, 2, 4096, 16),  # the delta-light scene's direct light (ReSTIR DI's depth)
    "veach-ajar": (64, 36, 13, 4096, 16),
    "staircase2": (64, 36, 65, 4096, 16),  # Mitsuba 0.5 as distributed; its own max_depth
}

# Options Mitsuba 3 refuses and restir accepts with a warning: taken out of the copy Mitsuba reads
MITSUBA_REFUSES = re.compile(r"<boolean name=\"(high_quality_edges|highQualityEdges)\"[^>]*/>")


def mitsuba_readable(path: str) -> str:
    """`path`, or, when it holds options Mitsuba 3 refuses (MITSUBA_REFUSES), a copy without them
    in a temporary folder beside links to the scene's files."""
    import tempfile

    text = open(path).read()
    if not MITSUBA_REFUSES.search(text):
        return path
    tmp, folder = tempfile.mkdtemp(), os.path.dirname(os.path.abspath(path))
    for entry in os.listdir(folder):
        os.symlink(os.path.join(folder, entry), os.path.join(tmp, entry))
    os.remove(os.path.join(tmp, os.path.basename(path)))
    copy = os.path.join(tmp, os.path.basename(path))
    with open(copy, "w") as f:
        f.write(MITSUBA_REFUSES.sub("", text))
    return copy


def load_for_mitsuba(mi, path, resx, resy, depth, spp):
    """The scene as Mitsuba 3 renders it at the given settings, and the integrator to render with.
    A scene without resx/resy/max_depth/spp parameters (as distributed) gets its film resized and
    a path integrator of that depth; options Mitsuba refuses are dropped (mitsuba_readable)."""
    path = mitsuba_readable(path)
    text = open(path).read()
    if "$resx" in text:
        return mi.load_file(path, resx=resx, resy=resy, max_depth=depth, spp=spp), None
    scene = mi.load_file(path)
    params = mi.traverse(scene.sensors()[0])
    params["film.size"] = [resx, resy]
    params.update()
    return scene, mi.load_dict({"type": "path", "max_depth": depth})


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--scenes", nargs="*", default=list(REFERENCES))
    ap.add_argument("--variant", default="llvm_ad_rgb")
    args = ap.parse_args()
    import mitsuba as mi

    from tests.data.feature_scene import SCENES

    mi.set_variant(args.variant)
    from restir.image_io import write_exr

    out_dir = os.path.join(HERE, "mitsuba")
    os.makedirs(out_dir, exist_ok=True)
    for name in args.scenes:
        resx, resy, depth, spp, k = REFERENCES[name]
        if name in SCENES:
            import tempfile

            path = SCENES[name](tempfile.mkdtemp())
        else:
            path = os.path.join(SHARED, name, "scene.xml")
        scene, integrator = load_for_mitsuba(mi, path, resx, resy, depth, spp)
        t0 = time.time()
        imgs = np.stack([np.asarray(mi.render(scene, integrator=integrator, spp=spp, seed=1000 + i), np.float64)[..., :3]
                         for i in range(k)])
        mean, var = imgs.mean(0), imgs.var(0, ddof=1) / k
        write_exr(os.path.join(out_dir, f"{name}.mean.exr"), mean.astype(np.float32))
        write_exr(os.path.join(out_dir, f"{name}.var.exr"), var.astype(np.float32))
        meta = {"scene": f"tests/data/feature_scene.py ({name})" if name in SCENES else f"shared/scenes/{name}/scene.xml", "mitsuba": mi.__version__, "variant": args.variant,
                "resx": resx, "resy": resy, "max_depth": depth, "spp_per_render": spp, "renders": k,
                "seconds": round(time.time() - t0, 1), "machine": platform.machine(),
                "command": "python tests/data/make_mitsuba_references.py --scenes " + name}
        with open(os.path.join(out_dir, f"{name}.json"), "w") as f:
            json.dump(meta, f, indent=2)
        print(name, meta)


if __name__ == "__main__":
    main()
