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


def test_loading_reports_progress_and_changes_nothing(tmp_path):
    """load_scene's progress: called before each top-level element and once at the end, counting
    up to the element count; the scene is the same with and without it."""
    xml = tmp_path / "scene.xml"
    rects = "".join(f'<shape type="rectangle"><transform name="to_world"><translate x="{i}"/></transform></shape>'
                    for i in range(5))
    xml.write_text(f'<scene version="3.0.0"><sensor type="perspective"><float name="fov" value="40"/><film type="hdrfilm">'
                   f'<integer name="width" value="4"/><integer name="height" value="4"/></film></sensor>{rects}</scene>')
    calls = []
    shown = restir.load_scene(str(xml), progress=lambda done, total: calls.append((done, total)))
    quiet = restir.load_scene(str(xml))
    assert calls == [(i, 6) for i in range(7)]  # the sensor and five shapes, then the end
    assert np.array_equal(shown.positions, quiet.positions)


def test_slow_load_shows_a_bar_and_its_time(tmp_path, monkeypatch):
    """The CLI's bar appears only once a load has taken SHOW_AFTER seconds (0 here, so any load
    is slow), and the load's time is said; with the real threshold a small scene prints neither."""
    from rich.console import Console

    from restir.cli import common

    def run(threshold):
        monkeypatch.setattr(common._LoadProgress, "SHOW_AFTER", threshold)
        con = Console(file=open(tmp_path / f"log{threshold}", "w+"), force_terminal=True, width=120)
        common.load_scene("builtin:cornell-box", {}, con)
        con.file.seek(0)
        return con.file.read()

    slow = run(0.0)
    assert "loading builtin:cornell-box" in slow and "loaded builtin:cornell-box in" in slow and "triangles)" in slow
    fast = run(60.0)
    assert "loading" not in fast and "loaded" not in fast
