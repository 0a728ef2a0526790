"""The GPU bundle's transfer (gpu/bundle.py, gpu/install.py) on a small archive: split into parts,
carried one call at a time, checked and unpacked; a damaged part refused before anything is
unpacked. (make gpu-rehearse runs the real bundle end to end.)"""
import io
import json
import lzma
import tarfile

import random

import pytest

from gpu.bundle import commands, split
from gpu.install import install


def small_archive(path):
    raw = io.BytesIO()
    with tarfile.open(fileobj=raw, mode="w") as tar:
        for name, data in (("site/pkg/__init__.py", b"VALUE = 42\n"),
                           ("site/pkg/lib.so.1", random.Random(1).randbytes(5000)),
                           ("scenes/a/scene.xml", b"<scene/>")):
            info = tarfile.TarInfo(name)
            info.size = len(data)
            tar.addfile(info, io.BytesIO(data))
        link = tarfile.TarInfo("site/pkg/lib.so")
        link.type, link.linkname = tarfile.SYMTYPE, "lib.so.1"
        tar.addfile(link)
    path.write_bytes(lzma.compress(raw.getvalue(), preset=1))


@pytest.fixture
def parts(tmp_path):
    archive = tmp_path / "bundle.tar.xz"
    small_archive(archive)
    out = tmp_path / "bundle"
    out.mkdir()
    second = tmp_path / "extras.tar.xz"
    small_archive(second)
    return split([archive, second], out, 1000, {"commit": "abc"})


def test_parts_carried_one_call_at_a_time_unpack_into_the_stash(parts, tmp_path):
    stash = tmp_path / "stash"
    assert len(parts) >= 2 and all(sum(f.stat().st_size for f in d.iterdir()) < 4000 for d in parts)
    for d in parts[:-1]:
        assert install(d, stash) == 0
        assert not (stash / "site").exists()  # waits for the last part
    assert install(parts[-1], stash) == 0
    assert (stash / "site/pkg/__init__.py").read_text() == "VALUE = 42\n"
    assert (stash / "site/pkg/lib.so").resolve() == (stash / "site/pkg/lib.so.1").resolve()
    assert (stash / "scenes/a/scene.xml").exists()
    assert not list(stash.glob("*.xz.*"))  # the parts are removed once unpacked


def test_a_damaged_part_is_refused_before_unpacking(parts, tmp_path, capsys):
    stash = tmp_path / "stash"
    first = next(f for f in parts[0].iterdir() if f.name != "manifest.json")
    first.write_bytes(b"x" + first.read_bytes()[1:])
    for d in parts:
        rc = install(d, stash)
    assert rc == 1 and "damaged" in capsys.readouterr().out
    assert not (stash / "site").exists()


def test_the_device_calls_fit_the_tool(parts):
    calls = commands(parts, scenes=True)
    assert len(calls) == len(parts)
    assert all(len(c["command"]) <= 2000 and len(c["carry"]) == 1 for c in calls)
    assert "gpu/check.py --device cuda" in calls[-1]["command"] and "check.py" not in calls[0]["command"]
    manifest = json.loads((parts[0] / "manifest.json").read_text())
    assert {p["archive"] for p in manifest["pieces"]} == {"bundle.tar.xz", "extras.tar.xz"}
    assert sum(p["bytes"] for p in manifest["pieces"]) == sum(a["bytes"] for a in manifest["archives"])
