"""`make gpu-check DEVICE=cpu QUICK=1`: the GPU check's every phase at toy sizes on the CPU, so that
the script a lent device machine runs cannot rot between draws (gpu/check.py, docs/guide/gpu.md)."""
import json
import os
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def test_the_gpu_check_runs_every_phase_at_toy_sizes(tmp_path):
    p = subprocess.run(["make", "gpu-check", "DEVICE=cpu", "QUICK=1", f"GPU_OUT={tmp_path}"],
                       cwd=ROOT, capture_output=True, text=True, timeout=1500)
    assert p.returncode == 0, p.stdout[-3000:] + p.stderr[-3000:]
    r = json.loads((tmp_path / "gpu_check.json").read_text())
    ph = r["phases"]
    assert list(ph) == ["environment", "agreement", "timing", "view", "tests", "equal_time"]
    assert not [n for n, x in ph.items() if "error" in x or "skipped" in x]
    assert ph["environment"]["warp"] and ph["environment"]["warp_device"]["name"]
    rows = ph["agreement"]["rows"]
    assert len(rows) == 8 and all(x["verdict"] in ("pass", "inconclusive") for x in rows)  # toy sizes: weak tests
    assert all(x["agreement"].startswith(("agree", "too weak")) for x in rows)
    timing = ph["timing"]["rows"]
    assert {x["method"] for x in timing} == {"pt", "restir-di", "restir-pt", "suffix-restir"}
    assert all(x["ms_per_frame"] > 0 and x["bytes_per_pixel"] > 0 and x["stages_ms"] for x in timing)
    assert ph["view"]["still"]["fps"] > 0 and ph["view"]["moving"]["width"] == 16  # half of 32 x 18
    assert ph["tests"]["returncode"] == 0 and ph["tests"]["counts"].get("passed", 0) >= 2
    methods = {m["method"] for m in ph["equal_time"]["methods"]}
    assert {"pt", "restir-pt", "suffix-restir"} <= methods
    md = (tmp_path / "gpu_check.md").read_text()
    assert "## Frame times" in md and "## Agreement with the CPU" in md and "## Equal time" in md
    assert "## restir view" in md
    assert len(list(tmp_path.iterdir())) <= 8  # what one device call brings back


@pytest.mark.slow
def test_the_bundle_installs_and_runs_the_check_as_a_device_would(tmp_path):
    """make gpu-rehearse: the bundle's parts installed one call at a time into a fresh Python 3.12
    with only the device image's packages, imported, and the check run from them (minutes: the
    first bundle downloads and compresses the packages)."""
    p = subprocess.run(["make", "gpu-rehearse"], cwd=ROOT, capture_output=True, text=True, timeout=5400,
                       env={**os.environ, "REHEARSE_DIR": str(tmp_path / "rehearse")})
    assert p.returncode == 0, p.stdout[-3000:] + p.stderr[-3000:]
    assert "rehearsal passed" in p.stdout
    r = json.loads((tmp_path / "rehearse" / "out" / "gpu_check.json").read_text())
    assert not [n for n, x in r["phases"].items() if "error" in x or "skipped" in x]
