"""The device side of the GPU bundle (gpu/bundle.py): standard library only, Python >= 3.8.

    python3 gpu/install.py .gpu-bundle/partK [--stash DIR]

Each call copies the part it was carried with to the stash (default /tmp/restir-gpu, outside the
working tree: it stays while the machine stays warm between calls). Once every part listed in
the manifest is there, it checks each part's SHA-256 and the whole archive's, and unpacks the
archive into the stash: site/ (the packages: PYTHONPATH=<stash>/site), scenes/, cpu_runs.npz.
A part that is missing or damaged is named, with exit status 1, before anything is unpacked.
"""
import argparse
import hashlib
import json
import lzma
import shutil
import sys
import tarfile
import time
from pathlib import Path

STASH = "/tmp/restir-gpu"
PART_NAME = "part{}"


def manifest_name() -> str:
    return "manifest.json"


def sha256_of(paths) -> str:
    h = hashlib.sha256()
    for p in paths:
        with open(p, "rb") as f:
            for block in iter(lambda: f.read(1 << 20), b""):
                h.update(block)
    return h.hexdigest()


class Chain:
    """The parts read one after another as one file (for lzma, without joining them on disk)."""

    def __init__(self, paths):
        self.paths, self.f = list(paths), None

    def read(self, n=-1):
        out = b""
        while n < 0 or len(out) < n:
            if self.f is None:
                if not self.paths:
                    break
                self.f = open(self.paths.pop(0), "rb")
            chunk = self.f.read(-1 if n < 0 else n - len(out))
            if not chunk:
                self.f.close()
                self.f = None
                continue
            out += chunk
        return out


def install(part_dir: Path, stash: Path) -> int:
    manifest = json.loads((part_dir / manifest_name()).read_text())
    stash.mkdir(parents=True, exist_ok=True)
    for f in part_dir.iterdir():
        if f.name != manifest_name():
            shutil.copy2(f, stash / f.name)
            print(f"stashed {f.name} ({f.stat().st_size / 2**20:.1f} MiB) in {stash}")
    (stash / manifest_name()).write_text(json.dumps(manifest))
    pieces = manifest["pieces"]
    missing = [p["file"] for p in pieces if not (stash / p["file"]).exists()]
    if missing:
        print(f"waiting for {', '.join(missing)}: carry the other parts in the next calls (docs/guide/gpu.md)")
        return 0
    for p in pieces:
        path = stash / p["file"]
        if path.stat().st_size != p["bytes"] or sha256_of([path]) != p["sha256"]:
            print(f"error: {p['file']} is damaged (size or SHA-256 differs from the manifest); carry its part again")
            return 1
    t = time.perf_counter()
    for sub in ("site", "scenes", "cpu_runs.npz"):
        target = stash / sub
        if target.is_dir():
            shutil.rmtree(target)
        elif target.exists():
            target.unlink()
    for archive in manifest["archives"]:
        paths = [stash / p["file"] for p in pieces if p["archive"] == archive["file"]]
        with lzma.LZMAFile(Chain(paths)) as xz, tarfile.open(fileobj=xz, mode="r|") as tar:
            for member in tar:
                if member.name.startswith("/") or ".." in Path(member.name).parts:
                    print(f"error: {member.name} would unpack outside {stash}")
                    return 1
                tar.extract(member, stash, **({"filter": "tar"} if hasattr(tarfile, "tar_filter") else {}))
        for path in paths:
            path.unlink()
    print(f"unpacked {', '.join(a['file'] for a in manifest['archives'])} (commit {manifest['commit'][:12]}) into "
          f"{stash} in {time.perf_counter() - t:.1f} s: PYTHONPATH={stash}/site")
    return 0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("part", help="the part's folder, as carried (.gpu-bundle/partK)")
    ap.add_argument("--stash", default=STASH, help="where the parts gather and the bundle unpacks")
    args = ap.parse_args(argv)
    return install(Path(args.part), Path(args.stash))


if __name__ == "__main__":
    sys.exit(main())
