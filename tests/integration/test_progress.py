"""Progress a user can see: within a frame (per part of its samples), and a notice while the
kernels compile for the first time."""
import os
import subprocess
import sys

import numpy as np
import pytest

import restir


@pytest.mark.parametrize("method,spp", [("pt", 12), ("restir-di", 3)])
def test_progress_advances_within_a_frame_and_changes_nothing(method, spp):
    scene = restir.load_scene("builtin:cornell-box-glossy", width=16, height=12)
    cfg = dict(method=method, spp=spp, frames=2, seed=4, max_depth=4 if method == "pt" else None)
    calls = []
    shown = restir.render(scene, progress=lambda done, total: calls.append((done, total)), **cfg)
    quiet = restir.render(scene, **cfg)
    # the same numbers in the same order: a frame split into several launches is the same image
    assert np.array_equal(shown.image, quiet.image) and np.array_equal(shown.sample_var, quiet.sample_var)
    done = [d for d, _ in calls]
    assert all(t == 2 for _, t in calls) and done == sorted(done) and done[-1] == 2
    assert any(0 < d < 1 for d in done), "no progress inside the first frame"


def test_first_compilation_says_so(tmp_path):
    """A fresh kernel cache (WARP_CACHE_PATH): the CLI says it is compiling; with the cache
    filled, the next run does not."""
    env = dict(os.environ, WARP_CACHE_PATH=str(tmp_path / "cache"))
    cmd = [sys.executable, "-m", "restir", "render", "builtin:cornell-box", "--width", "8", "--height", "8",
           "--spp", "1", "-o", str(tmp_path / "x.npy")]
    first = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=600)
    assert first.returncode == 0, first.stderr
    assert "compiling kernels" in first.stderr, first.stderr
    second = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=600)
    assert second.returncode == 0 and "compiling kernels" not in second.stderr, second.stderr
