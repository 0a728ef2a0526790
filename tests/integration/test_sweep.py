"""Fan-out: `restir sweep` and `restir validate` on a local process pool give bitwise the same
numbers as in one process; the sweep on a local Ray cluster (slow tier) the same as on the pool."""
import csv
import json

import numpy as np
import pytest

import restir
from restir.cli import main
from restir.compare.sweep import parse_grid, sweep
from restir.config import ConfigError, RenderConfig
from restir.validation import IndependentRuns

GRID = ["spatial.neighbors=1,4"]
KW = dict(seeds=4, frames=4, width=24, height=24, reference_spp=32)


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("RESTIR_CACHE", str(tmp_path / "cache"))


def _same(a, b):
    assert [r["point"] for r in a.rows] == [r["point"] for r in b.rows]
    for x, y in zip(a.rows, b.rows):
        assert x["seed"] == y["seed"] and x["image_mean"] == y["image_mean"], (x, y)
        assert x["relmse_accumulated"] == y["relmse_accumulated"] and x["relmse_frame"] == y["relmse_frame"]
    for x, y in zip(a.comparison.methods, b.comparison.methods):
        assert np.array_equal(x.image, y.image)


def test_sweep_pool_equals_one_process(cache):
    scene = restir.load_scene("builtin:cornell-box")
    one = sweep(scene, "restir-di", GRID, workers=1, **KW)
    pool = sweep(scene, "restir-di", GRID, workers=2, **KW)
    _same(one, pool)
    assert len(one.rows) == 8 and len(one.summary) == 2 and all(e["seeds"] == 4 for e in one.summary)
    assert len({r["image_mean"] for r in one.rows}) == 8  # every seed and setting its own render


@pytest.mark.slow
def test_sweep_on_a_local_ray_cluster(cache):
    ray = pytest.importorskip("ray")  # the test extra installs it
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    try:
        scene = restir.load_scene("builtin:cornell-box")
        on_ray = sweep(scene, "restir-di", GRID, ray="auto", **KW)
    finally:
        ray.shutdown()
    _same(on_ray, sweep(scene, "restir-di", GRID, workers=2, **KW))


def test_validate_runs_on_the_pool():
    scene = restir.load_scene("builtin:cornell-box")
    cfg = RenderConfig(method="restir-di", spp=1, frames=4, width=16, height=16)
    a = IndependentRuns(scene, cfg, 4, seed0=10, workers=1)
    b = IndependentRuns(scene, cfg, 4, seed0=10, workers=2)
    assert np.array_equal(a.batches, b.batches) and a.counters == b.counters


def test_sweep_cli_writes_tables_and_report(cache, tmp_path, capsys):
    out = tmp_path / "sw"
    code = main(["sweep", "builtin:cornell-box", "--method", "restir-di", "--grid", "spatial.neighbors=1,4",
                 "--grid", "candidates=4,8", "--seeds", "2", "--frames", "3", "--width", "16", "--height", "16",
                 "--reference-spp", "16", "--out", str(out), "--workers", "2", "--quiet"])
    assert code == 0
    data = json.load(open(out / "sweep.json"))
    rows = list(csv.DictReader(open(out / "sweep.csv")))
    assert len(rows) == len(data["rows"]) == 8 and len(data["summary"]) == 4
    assert {r["point"] for r in rows} == {f"spatial.neighbors={n},candidates={c}" for n in (1, 4) for c in (4, 8)}
    assert float(rows[0]["relmse_accumulated"]) == pytest.approx(data["rows"][0]["relmse_accumulated"])
    assert (out / "report" / "index.html").is_file()


def test_grid_errors():
    assert parse_grid([], "pt") == [{}]
    assert len(parse_grid(["spp=1,2,4", "strategy=nee,mis"], "pt")) == 6
    for items, msg in ((["nope=1,2"], "unknown setting"), (["spp=0"], "spp"), (["candidates"], "key=value"),
                       (["candidates=1", "candidates=2"], "twice"), (["candidates=x"], "candidates")):
        with pytest.raises(ConfigError, match=msg):
            parse_grid(items, "restir-di")
    with pytest.raises(ConfigError, match="unknown method"):
        parse_grid([], "nope")
