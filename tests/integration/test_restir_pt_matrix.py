"""Slow tier: the ReSTIR PT stage-isolation matrix (TESTING.md 5.6) against the path tracer at
the same max_depth, with independent runs on both sides (restir.validation.IndependentRuns).

Every configuration: K = 64 independent runs of T = 8 frames at 32x32, its statistic per run
the run's average image; the reference is the path tracer over 64 runs x 8 frames x 16 spp,
rendered once per scene and camera motion. Welch z per channel at image, tile (8x8) and pixel
level, alpha = 1e-3 per configuration; the MDB (80% power, image level) is printed and bounded
per scene (the emissive-cap sphere has an exact reference instead).

Scenes: the glossy Cornell box, veach-bidir and veach-mis (shared scenes), the emissive-cap
sphere (A1) and the indirect room (light hidden from the camera, glossy surfaces).
"""
import functools

import pytest

import restir
from restir.scene.builtin import sphere_cap_radiance
from restir.validation import IndependentRuns
from tests.integration.test_path_tracer import ANALYTIC_REL_TOL, check
from tests.shared_scenes import scene_path

RUNS, FRAMES, SIZE = 64, 8, 32
NO_REUSE = {"temporal": False, "spatial.rounds": 0}
SPATIAL = {"temporal": False}
TEMPORAL = {"spatial.rounds": 0}

MATRIX = {
    "C1-candidates-1": ({**NO_REUSE}, "none"),
    "C1-candidates-4": ({**NO_REUSE, "candidates": 4}, "none"),
    **{f"C3-{shift}-k{k}": ({**SPATIAL, "shift": shift, "spatial.neighbors": k}, "none")
       for shift in ("hybrid", "reconnection", "replay") for k in (1, 3, 8)},
    **{f"C3-{shift}-k3-rounds-{r}": ({**SPATIAL, "shift": shift, "spatial.rounds": r}, "none")
       for shift in ("hybrid", "reconnection", "replay") for r in (2, 3)},
    "C2-cap-1": ({**TEMPORAL, "temporal.cap": 1.0}, "none"),
    "C2-cap-20": ({**TEMPORAL, "temporal.cap": 20.0}, "none"),
    "C2-no-cap": ({**TEMPORAL, "temporal.cap": 0.0}, "none"),
    "C4-defaults": ({}, "none"),
    "C4-direct-pt": ({"direct": "pt"}, "none"),
    "C4-k8-rounds-2": ({"spatial.neighbors": 8, "spatial.rounds": 2}, "none"),
    "C4-orbit": ({}, "orbit"),
    "C4-dolly": ({}, "dolly"),
}
CAMERA_SPEED = {"none": 1.0, "orbit": 3.0, "dolly": 0.02}
# scene: (loader, max_depth, MDB bound)
SCENES = {
    "cornell-box-glossy": (lambda: restir.load_scene("builtin:cornell-box-glossy"), 5, 0.05),
    # veach-bidir and veach-mis: inconclusive at this cost (measured: no |z| above 2 at image level,
    # but MDB 15.6% and 27% on every configuration, with median pixel skew 3.5 and excess kurtosis
    # 13-16: the reference path tracer's and the canonical paths' heavy tails; the tile level then
    # also exceeds its normal-theory threshold in 3 of 25 veach-bidir configurations, at image
    # |z| < 2). Expected failures until the runs are long enough: issue 9.
    "veach-bidir": pytest.param((lambda: restir.load_scene(str(scene_path("veach-bidir"))), 5, 0.06),
                                marks=pytest.mark.xfail(reason="inconclusive: heavy tails, MDB 16%", strict=False)),
    "veach-mis": pytest.param((lambda: restir.load_scene(str(scene_path("veach-mis"))), 3, 0.06),
                              marks=pytest.mark.xfail(reason="inconclusive: heavy tails, MDB 27%", strict=False)),
    "indirect-room": (lambda: restir.load_scene("builtin:indirect-room"), 5, 0.06),
    "sphere-cap": (lambda: restir.load_scene("builtin:sphere-cap", albedo=0.5, radiance=1.0, phi=0.05), 5, 0.01),
}


def independent_runs(scene, method, settings, motion, spp, seed0, max_depth):
    cfg = restir.RenderConfig(method=method, spp=spp, frames=FRAMES, width=SIZE, height=SIZE, max_depth=max_depth,
                              settings=settings, camera_motion=motion, camera_speed=CAMERA_SPEED[motion])
    return IndependentRuns(scene, cfg, RUNS, seed0)


def scene_row(name):
    row = SCENES[name]
    return row.values[0] if hasattr(row, "values") else row


@functools.lru_cache(maxsize=None)
def reference(name, motion):
    load, depth, _ = scene_row(name)
    return independent_runs(load(), "pt", {}, motion, 16, 9000, depth)


@pytest.mark.slow
@pytest.mark.parametrize("config", list(MATRIX))
@pytest.mark.parametrize("name", [pytest.param(k, marks=v.marks) if hasattr(v, "marks") else k
                                  for k, v in SCENES.items()])
def test_restir_pt_matrix(name, config):
    load, depth, bound = scene_row(name)
    settings, motion = MATRIX[config]
    r = independent_runs(load(), "restir-pt", settings, motion, 1, 100, depth)
    assert all(s["settings"]["debug.mutation"] == "none" for s in r.stats)
    assert not any(s["reuse_dead"] for s in r.stats), r.stats[0]["shifts"]
    if name == "sphere-cap":
        rep = check(r, sphere_cap_radiance(0.5, 1.0, 0.05, depth), rel_tol=ANALYTIC_REL_TOL)
    else:
        ref = reference(name, motion)
        rep = check(r, ref.image, ref.batch_variance_of_mean, other=ref, tile=8)
    print(name, config, f"K={RUNS} T={FRAMES} MDB={rep.mdb:.4f}", r.stats[0]["shifts"], r.stats[0]["final_samples"])
    assert rep.mdb < bound
