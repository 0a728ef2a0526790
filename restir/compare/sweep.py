"""`sweep`: one method over a grid of settings and seeds, every render an independent task fanned
out locally or on Ray (restir/fanout.py), measured against one reference.

Each grid point x seed renders `frames` frames (keeping them, for the per-frame errors); the
table has one row per render and the summary one per grid point (mean and standard deviation
over seeds). The report shows each grid point's first seed as one image of the viewer.
"""
import csv
import dataclasses
import itertools
import json
import os

import numpy as np

from .. import limits
from ..config import ConfigError, RenderConfig
from .frames import FrameStats
from .runner import Comparison, measure
from .reference import load_reference_file, path_traced_reference


def parse_grid(items, method: str) -> list:
    """['key=v1,v2', 'spp=1,2'] -> the list of setting dicts of their cartesian product (values as
    given; each checked against the method's settings, spp as the samples per pixel per frame)."""
    from ..integrators import METHODS

    if method not in METHODS:
        raise ConfigError(f"unknown method '{method}' (available: {', '.join(METHODS)})")
    axes = []
    for item in items:
        key, eq, values = item.partition("=")
        key = key.strip()
        vals = [v.strip() for v in values.split(",") if v.strip()]
        if not eq or not vals:
            raise ConfigError(f"--grid {item}: expected key=value1,value2,...")
        if any(key == k for k, _ in axes):
            raise ConfigError(f"--grid {key} is given twice")
        for v in vals:
            if key == "spp":
                if not v.isdigit() or int(v) < 1:
                    raise ConfigError(f"--grid {item}: spp '{v}' is not an integer >= 1")
            else:
                try:
                    METHODS[method].Settings.from_overrides({key: v})
                except ConfigError as e:
                    raise ConfigError(f"--grid {item}: {e}") from None
        axes.append((key, vals))
    if not axes:
        return [{}]
    return [dict(zip([k for k, _ in axes], combo)) for combo in itertools.product(*[v for _, v in axes])]


def point_label(point: dict) -> str:
    return ",".join(f"{k}={v}" for k, v in point.items()) or "defaults"


@dataclasses.dataclass
class Sweep:
    comparison: Comparison   # seed 0 of every grid point, for the report
    rows: list               # one per (grid point, seed)
    summary: list            # one per grid point: mean and std over seeds

    def to_dict(self) -> dict:
        return {"scene": self.comparison.scene, "width": self.comparison.width, "height": self.comparison.height,
                "budget": self.comparison.budget, "reference": self.comparison.reference.source,
                "rows": self.rows, "summary": self.summary}


def sweep(scene, method: str, grid, *, seeds: int = 1, frames: int = 16, spp: int = 1, warmup: int = 4,
          reference: str | None = None, reference_spp: int = 1024, width=None, height=None, max_depth=None,
          device: str = "cpu", workers: int | None = None, ray: str | None = None, jitter: bool = True,
          progress=None) -> Sweep:
    """Render `method` at every point of `grid` (a list of --grid strings or of setting dicts) for
    seeds 0..seeds-1, `frames` frames each, fanned out (workers / ray: see fanout.run_tasks);
    `jitter` as RenderConfig.jitter, for the reference too."""
    from ..api import check_device, sized_scene
    from ..fanout import run_tasks

    from ..scene.animation import refuse_for_one_reference

    refuse_for_one_reference(scene, "sweep")
    points = grid if grid and isinstance(grid[0], dict) else parse_grid(grid or [], method)
    if seeds < 1 or frames < 1 or spp < 1:
        raise ConfigError("seeds, frames and spp must be >= 1")
    problem = limits.runs_problem("--seeds", seeds, 1)
    if problem:
        raise ConfigError(problem)
    base = RenderConfig(method=method, frames=frames, spp=spp, width=width, height=height, max_depth=max_depth,
                        device=device, keep_frames=True, jitter=jitter)
    base.validate()
    check_device(base)
    sized = sized_scene(scene, base)
    base = dataclasses.replace(base, width=sized.camera.width, height=sized.camera.height)
    from ..integrators import METHODS

    ref_cfg = base
    fixed = METHODS[method].FIXED_MAX_DEPTH
    if fixed is not None and max_depth is None:
        ref_cfg = dataclasses.replace(base, max_depth=fixed)
    if reference is not None:
        ref = load_reference_file(reference, base.width, base.height)
    else:
        ref = path_traced_reference(scene, reference_spp, ref_cfg)
    configs = []
    for point in points:
        settings = {k: v for k, v in point.items() if k != "spp"}
        for seed in range(seeds):
            configs.append((point, dataclasses.replace(base, settings=settings, seed=seed,
                                                       spp=int(point.get("spp", spp)))))
    results = run_tasks([(scene, cfg) for _, cfg in configs], workers=workers, ray=ray, progress=progress)
    rows, firsts = [], []
    for (point, cfg), r in zip(configs, results):
        ms = r.stats["ms_per_frame"]
        fs = FrameStats(ref, warmup)
        for x in r.frame_images:
            fs.add(x)
        label = point_label(point)
        m = measure(label, cfg, fs, [ms * 1e-3 * (i + 1) for i in range(fs.count)], ref, warmup, r.stats)
        rows.append({"point": label, **{k: str(v) for k, v in point.items()}, "seed": cfg.seed,
                     **{k: v for k, v in m.metrics.items() if k not in ("mean_z", "mean_mdb")},
                     "image_mean": float(np.mean(r.image))})
        if cfg.seed == 0:
            firsts.append(m)
    summary = []
    for point in points:
        label = point_label(point)
        mine = [row for row in rows if row["point"] == label]
        entry = {"point": label, "seeds": len(mine)}
        for key in ("relmse_frame", "relmse_accumulated", "mape", "ms_per_frame", "image_mean"):
            vals = np.array([row[key] for row in mine], np.float64)
            entry[key] = float(vals.mean())
            entry[key + "_std"] = float(vals.std(ddof=1)) if len(vals) > 1 else 0.0
        summary.append(entry)
    budget = f"{frames} frames x {spp} spp per render, {seeds} seed(s) per grid point"
    comparison = Comparison(scene.name, base.width, base.height, budget, warmup, ref, firsts)
    return Sweep(comparison, rows, summary)


def write_tables(result: Sweep, json_path: str | None, csv_path: str | None) -> None:
    if json_path:
        with open(json_path, "w") as f:
            json.dump(result.to_dict(), f, indent=2, default=str)
    if csv_path:
        keys = []
        for row in result.rows:
            keys += [k for k in row if k not in keys]
        with open(csv_path, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=keys)
            w.writeheader()
            w.writerows(result.rows)


def write_sweep(result: Sweep, folder: str) -> str:
    """sweep.json, sweep.csv and the report (report/index.html) in `folder`; returns the report's path."""
    from .report import write_report

    os.makedirs(folder, exist_ok=True)
    write_tables(result, os.path.join(folder, "sweep.json"), os.path.join(folder, "sweep.csv"))
    return write_report(result.comparison, os.path.join(folder, "report"))
