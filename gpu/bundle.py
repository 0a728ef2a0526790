"""`make gpu-bundle`: what a device machine needs and does not have, packed to travel in parts.

A device call carries the working tree and at most 64 MiB (docs/guide/gpu.md). The machine has Python,
numpy, scipy, pytest, pytest-xdist, rich and Pillow, but not Warp, whose wheel alone is 149 MB.
This script:

1. downloads the wheels of the packages the device lacks, at the versions installed here, for
   the device's Python (cp312, manylinux x86-64): warp-lang, OpenEXR, plyfile, flip-evaluator,
   pyoidn with cffi and pycparser (Embree and plotly stay behind: the CPU tracer falls back to
   Warp's BVH, and the HTML report is not part of the check);
2. unpacks them into one site folder (what `pip install --target` makes of these wheels), less
   Warp's tests and examples and OIDN's libraries for AMD and Intel GPUs; files that are copies
   of one another (a library under its three names) become links;
3. adds the scenes the check renders (veach-ajar, staircase2, and veach-bidir for a test, from
   ../shared/scenes), the shipped
   kernels compiled for sm_90 in a Warp kernel cache, and the CPU side of the check's agreement
   phase (compiled and rendered here: the device's minutes are scarcer);
4. packs the packages as one .tar.xz and the rest as another, and splits them into parts that
   each fit in one call beside the working tree: .gpu-bundle/part1/, part2/, ... each with the
   manifest (sizes, SHA-256s, commit, the commands to run).

gpu/install.py unpacks it on the device, part by part. The wheels are cached in
.gpu-bundle/wheels and the packed site in .gpu-bundle/cache (keyed by the wheels), so that a
second bundle only redoes the scenes, the kernels and CPU runs (when the sources changed) and
the split.
"""
import argparse
import hashlib
import io
import json
import lzma
import os
import shutil
import subprocess
import sys
import tarfile
import zipfile
from importlib import metadata
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from gpu.install import PART_NAME, STASH, manifest_name  # noqa: E402

PACKAGES = ["warp-lang", "OpenEXR", "plyfile", "flip-evaluator", "pyoidn", "cffi", "pycparser"]
CALL_LIMIT = 64 * 2**20  # what one device call carries: the working tree and the named paths
MARGIN = 2 * 2**20
PLATFORMS = ["manylinux_2_28_x86_64", "manylinux_2_27_x86_64", "manylinux_2_17_x86_64", "manylinux2014_x86_64",
             "manylinux1_x86_64"]
# Left out of the site folder: Warp's own tests and examples (about 12 MB), OIDN's AMD (HIP) and
# Intel (SYCL, Level Zero) devices and their loaders (about 45 MB).
DROP = ("warp/tests/", "warp/examples/", "libOpenImageDenoise_device_hip", "libOpenImageDenoise_device_sycl",
        "libsycl.so", "libur_", "libumf.so")
SCENES = ("veach-ajar", "staircase2", "veach-bidir")  # the check's timing and equal time; a Jacobian test


def tree_bytes() -> int:
    """What the working tree sends with every call: tracked files and untracked ones git does not
    ignore (the device tool's rule)."""
    out = subprocess.run(["git", "ls-files", "-z", "--cached", "--others", "--exclude-standard"], cwd=ROOT,
                         capture_output=True, check=True).stdout
    return sum((ROOT / p).stat().st_size for p in out.decode().split("\0") if p and (ROOT / p).is_file())


def download(wheels: Path, python: str) -> list[Path]:
    wheels.mkdir(parents=True, exist_ok=True)
    found = []
    for name in PACKAGES:
        version = metadata.version(name)
        norm = name.lower().replace("-", "_")
        have = [w for w in wheels.glob("*.whl") if w.name.lower().startswith(norm + "-" + version.lower())
                and (f"cp{python}" in w.name or "py3-none" in w.name or "py2.py3" in w.name)]
        if not have:
            cmd = [sys.executable, "-m", "pip", "download", "-q", "--no-deps", "--only-binary=:all:",
                   "--python-version", python, "--implementation", "cp", "-d", str(wheels), f"{name}=={version}"]
            for p in PLATFORMS:
                cmd += ["--platform", p]
            subprocess.run(cmd, check=True)
            have = [w for w in wheels.glob("*.whl") if w.name.lower().startswith(norm + "-" + version.lower())]
        found.append(sorted(have)[-1])
    return found


def site_files(wheel_paths: list[Path]):
    """(path in the site folder, bytes, mode) of every file the wheels install, less DROP."""
    for whl in wheel_paths:
        with zipfile.ZipFile(whl) as z:
            for info in z.infolist():
                if info.is_dir() or any(d in info.filename for d in DROP):
                    continue
                mode = (info.external_attr >> 16) & 0o777 or 0o644
                yield info.filename, z.read(info), mode


def pack_site(wheel_paths: list[Path], cache: Path) -> Path:
    """site.tar (uncompressed; compressed with the rest later), cached by the wheels' names."""
    key = hashlib.sha256("\n".join(sorted(w.name for w in wheel_paths)).encode()).hexdigest()[:12]
    out = cache / f"site-{key}.tar"
    if out.exists():
        return out
    cache.mkdir(parents=True, exist_ok=True)
    seen: dict[str, str] = {}  # content hash -> first path: later copies become links
    tmp = out.with_suffix(".part")
    with tarfile.open(tmp, "w") as tar:
        for name, data, mode in sorted(site_files(wheel_paths), key=lambda x: x[0]):
            arc = "site/" + name
            digest = hashlib.sha256(data).hexdigest()
            if digest in seen and len(data) > 65536 and os.path.dirname(seen[digest]) == os.path.dirname(arc):
                info = tarfile.TarInfo(arc)
                info.type, info.linkname = tarfile.SYMTYPE, os.path.basename(seen[digest])
                tar.addfile(info)
                continue
            seen.setdefault(digest, arc)
            info = tarfile.TarInfo(arc)
            info.size, info.mode = len(data), mode
            tar.addfile(info, io.BytesIO(data))
    tmp.rename(out)
    return out


def precompile(cache: Path, source_hash: str) -> Path:
    """The shipped kernels compiled for the device's card into a Warp kernel cache (sm_90 cubins,
    what Warp 1.19 loads on an H100 or H200 when its CUDA toolkit, 13.4, is newer than the
    driver): the device loads them instead of compiling them, about 3 minutes of one core here.
    Two processes (NVRTC is single-threaded), ReSTIR PT's and Suffix ReSTIR's modules on separate
    ones. Cached by the sources' hash."""
    from restir.kernel_modules import KERNEL_MODULES

    out = cache / f"kernels-{source_hash}"
    if (out / "complete").exists():
        return out
    shutil.rmtree(out, ignore_errors=True)
    env = dict(os.environ, WARP_CACHE_PATH=str(out))
    procs = [subprocess.Popen([sys.executable, __file__, "--precompile", *mods], env=env, cwd=ROOT)
             for mods in (KERNEL_MODULES[0::2], KERNEL_MODULES[1::2])]
    if any(p.wait() != 0 for p in procs):
        raise SystemExit("error: compiling the kernels for sm_90 failed")
    for f in out.rglob("*.cu"):  # the generated sources: not needed to load
        f.unlink()
    (out / "complete").touch()
    return out


def compile_for_device(modules: list[str]) -> None:
    """(In a process of its own, WARP_CACHE_PATH set) compile `modules` for sm_90 into the cache."""
    import warp as wp

    import restir  # noqa: F401  (the project's Warp options, which the modules' hashes include)
    from restir.kernel_modules import import_all

    wp.init()
    import_all()
    for m in modules:
        wp.compile_aot_module(m, arch=[90])
        print(f"  compiled {m} for sm_90", flush=True)


def xz(raw: Path, out: Path) -> None:
    """raw -> out (.xz, preset 9), raw removed."""
    if shutil.which("xz"):  # multi-threaded, the same format as Python's lzma
        subprocess.run(["xz", "-9", "-T0", "-f", "-k", "-c", str(raw)], stdout=open(out, "wb"), check=True)
    else:
        with open(raw, "rb") as f, lzma.open(out, "wb", preset=9) as g:
            shutil.copyfileobj(f, g, 1 << 20)
    raw.unlink()


def compressed_site(site_tar: Path) -> Path:
    """The site tar compressed once (minutes) and cached beside it."""
    out = site_tar.with_suffix(".tar.xz")
    if not out.exists():
        tmp = out.with_suffix(".part")
        raw = site_tar.with_suffix(".copy")
        shutil.copy(site_tar, raw)
        xz(raw, tmp)
        tmp.rename(out)
    return out


def extras_archive(extra: dict[str, Path], out: Path) -> None:
    """The scenes and the CPU runs (they change with the code and the shared scenes) as a small
    .tar.xz of their own, so that a new bundle does not compress the packages again."""
    raw = out.with_suffix(".tmp")
    with tarfile.open(raw, "w") as tar:
        for arc, path in extra.items():
            tar.add(path, arcname=arc)
    xz(raw, out)


def split(archives: list[Path], folder: Path, part_bytes: int, manifest: dict) -> list[Path]:
    """Every archive cut into pieces of at most part_bytes, packed into as few parts (folders of
    at most part_bytes) as fit, in order; the manifest lists each piece with its SHA-256."""
    for old in folder.glob("part*"):
        shutil.rmtree(old)
    manifest.update(archives=[], pieces=[])
    parts: list[Path] = []
    used = part_bytes
    for archive in archives:
        manifest["archives"].append({"file": archive.name, "bytes": archive.stat().st_size,
                                     "sha256": sha256(archive)})
        remaining = archive.stat().st_size
        with open(archive, "rb") as f:
            k = 0
            while remaining > 0:
                if used >= part_bytes:
                    parts.append(folder / PART_NAME.format(len(parts) + 1))
                    parts[-1].mkdir(parents=True)
                    used = 0
                data = f.read(min(part_bytes - used, remaining))
                remaining -= len(data)
                k += 1
                piece = parts[-1] / f"{archive.name}.{k:03d}"
                piece.write_bytes(data)
                used += len(data)
                manifest["pieces"].append({"archive": archive.name, "file": piece.name, "bytes": len(data),
                                           "sha256": hashlib.sha256(data).hexdigest()})
    for d in parts:
        (d / manifest_name()).write_text(json.dumps(manifest, indent=1))
    return parts


def sha256(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def commands(parts: list[Path], scenes: bool, kernels: bool = True) -> list[dict]:
    """The device calls, in order: each carries one part; the last installs and runs the check."""
    calls = []
    for i, d in enumerate(parts):
        rel = os.path.relpath(d, ROOT)
        cmd = f"python3 gpu/install.py {rel}"
        if i == len(parts) - 1:
            cache = f"WARP_CACHE_PATH={STASH}/kernels " if kernels else ""
            cmd += (f" && {cache}PYTHONPATH={STASH}/site PYTHONUNBUFFERED=1 python3 gpu/check.py --device cuda"
                    f" --out $OUT{f' --scenes {STASH}/scenes' if scenes else ''} --cpu-runs {STASH}/cpu_runs.npz")
        calls.append({"carry": [rel], "command": cmd, "timeout_s": 600 if i == len(parts) - 1 else 120})
    return calls


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default=str(ROOT / ".gpu-bundle"), help="the bundle's folder (git-ignored)")
    ap.add_argument("--python", default="312", help="the device's Python, as pip's --python-version (312)")
    ap.add_argument("--scenes", default=os.environ.get("RESTIR_SCENES") or str(ROOT.parent / "shared" / "scenes"), help="where veach-ajar/ and "
                    "staircase2/ are")
    ap.add_argument("--no-cpu-runs", action="store_true", help="leave the agreement phase's CPU runs to the device")
    ap.add_argument("--part-mib", type=float, help="part size (default: what fits in a call beside the tree)")
    ap.add_argument("--no-kernels", action="store_true", help="leave the kernels to be compiled on the device")
    ap.add_argument("--precompile", nargs="+", metavar="MODULE", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.precompile:
        compile_for_device(args.precompile)
        return 0
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    wheels = download(out / "wheels", args.python)
    print("wheels:", ", ".join(w.name for w in wheels), flush=True)
    site = pack_site(wheels, out / "cache")
    extra = {}
    scenes = Path(args.scenes)
    for s in SCENES:
        if (scenes / s / "scene.xml").exists():
            extra[f"scenes/{s}"] = scenes / s
        else:
            print(f"no {scenes / s}/scene.xml: the check's timing leaves that scene out", flush=True)
    from gpu.check import source_hash

    if not args.no_kernels:
        print("compiling the kernels for sm_90 (cached by the sources)", flush=True)
        extra["kernels"] = precompile(out / "cache", source_hash())
    if not args.no_cpu_runs:
        from gpu.check import Sizes, save_cpu_runs

        runs = out / "cache" / "cpu_runs.npz"
        print("rendering the agreement phase's CPU runs", flush=True)
        save_cpu_runs(str(runs), Sizes())
        extra["cpu_runs.npz"] = runs
    print("compressing the packages (xz -9; cached after the first time)", flush=True)
    archives = [compressed_site(site)]
    if extra:
        archives.append(out / "cache" / "extras.tar.xz")
        extras_archive(extra, archives[-1])

    tree = tree_bytes()
    part_bytes = int(args.part_mib * 2**20) if args.part_mib else CALL_LIMIT - tree - MARGIN
    from gpu.check import commit

    manifest = {"commit": commit(), "source_hash": source_hash(), "python": args.python,
                "wheels": [w.name for w in wheels], "tree_bytes": tree, "part_limit_bytes": part_bytes}
    parts = split(archives, out, part_bytes, manifest)
    manifest["calls"] = commands(parts, any(k.startswith("scenes/") for k in extra), "kernels" in extra)
    for d in parts:
        (d / manifest_name()).write_text(json.dumps(manifest, indent=1))
    (out / "calls.json").write_text(json.dumps(manifest["calls"], indent=1))
    print(f"\n{len(parts)} parts of at most {part_bytes / 2**20:.1f} MiB (the working tree sends "
          f"{tree / 2**20:.1f} MiB with each call); the device calls, in order (also in {out / 'calls.json'}):")
    for c in manifest["calls"]:
        print(f"  run(carry={c['carry']}, timeout_s={c['timeout_s']}, command={c['command']!r})")
        assert len(c["command"]) <= 2000
    return 0


if __name__ == "__main__":
    sys.exit(main())
