"""Temporal reuse under scene motion (docs/theory/restir_di.md#temporal-reuse-under-motion,
docs/theory/restir_pt.md#temporal-reuse-under-motion): ReSTIR DI, and ReSTIR PT with the replay
shift (max_depth 3, the same scenes and test), with their biased switches detected; the shifts and
methods that cannot follow motion refused.

Each run renders 8 frames of an animated Cornell box (tests/scenes.py motion_scene: a sliding
block, a moving light, a light switched off and on, a block that vanishes and comes back, and all
four together) at 32x32, and its statistic is its 8 frames side by side (IndependentRuns
per_frame), so that every frame is tested against the path tracer's runs of the same frame:
64 independent runs of ReSTIR DI (4 spp a frame, the defaults: temporal and spatial reuse)
against 64 of the direct-only path tracer at 16 spp. 4 spp, not 1, for the pixels on the edge of
the moving light: where it covers 5% of a pixel, 64 runs of 1 sample all miss it with probability
0.04, and a side whose runs are all 0 has no variance for the z-test to see. Welch z per channel at image, tile (8x8) and
pixel level, alpha = 1e-3 per test (restir/validation/stats.py); the MDB (80% power, image level)
is bounded by 6%.

The power checks: the history evaluated in the current scene (the biased switch
temporal.previous_scene=false, and the mutation current_scene_history that does the same inside
the kernel) and the previous frame's lights replaced by the current ones fail the same test
where the motion makes them differ. Measured when these tests were written: the unbiased cells
pass with max |z| 3.3 (tile) and 6.3 (pixel; the pixel threshold is about 6.9 at these sizes), the
biased switch fails with tile |z| 18.6 (sliding block), 11.1 (moving light), 362 (switched light)
and 34.8 (vanishing block).

A motion vector from the camera alone is not a bias (any choice of the previous pixel made from
geometry keeps the weights unbiased); it loses the history on moving objects, which
tests/unit/test_animation.py checks directly.
"""
import functools

import numpy as np
import pytest

import restir
from restir.validation import IndependentRuns
from restir.validation.check import compare
from tests.helpers import check
from tests.scenes import MOTION_KINDS, motion_scene

RUNS, FRAMES, SIZE = 64, 8, 32
MAX_MDB = 0.06
DI_SPP = 4


@functools.lru_cache(maxsize=None)
def scene(kind):
    return motion_scene(kind)


def runs(kind, method, spp, seed0, camera="none", settings=None, allow_mutation=False, depth=2):
    """64 independent runs, each its 8 frames side by side (direct light alone unless `depth`)."""
    cfg = restir.RenderConfig(method=method, spp=spp, frames=FRAMES, width=SIZE, height=SIZE, max_depth=depth,
                              camera_motion=camera, camera_speed=3.0, settings=settings or {})
    return IndependentRuns(scene(kind), cfg, RUNS, seed0, allow_mutation=allow_mutation, per_frame=True)


@functools.lru_cache(maxsize=None)
def reference(kind, camera="none", depth=2):
    return runs(kind, "pt", 16, 500_000, camera, depth=depth)


@pytest.mark.parametrize("kind,camera", [(k, "none") for k in MOTION_KINDS] + [("all", "orbit")])
def test_restir_di_under_motion_matches_the_path_tracer_frame_by_frame(kind, camera):
    di = runs(kind, "restir-di", DI_SPP, 10_000, camera)
    ref = reference(kind, camera)
    rep = check(di, ref.image, ref.batch_variance_of_mean, other=ref, tile=8)
    print(kind, camera, f"MDB {rep.mdb:.4f}", di.counters)
    assert rep.mdb < MAX_MDB


@pytest.mark.parametrize("kind,settings", [
    ("occluder", {"temporal.previous_scene": False}),
    ("appear", {"temporal.previous_scene": False}),
    ("switch", {"debug.mutation": "current_scene_history"}),
    ("light", {"debug.mutation": "previous_lights_dropped"}),
    ("switch", {"debug.mutation": "previous_lights_dropped"}),
])
def test_history_evaluated_in_the_wrong_scene_is_detected(kind, settings):
    """At 1 spp a frame, where every sample's history is a frame earlier (at 4 spp three of four
    samples reuse a sample of their own frame, and the moving light's defect was not seen). Detected
    means at tile level, so that no rare pixel (the light's edge, above) can be the reason."""
    di = runs(kind, "restir-di", 1, 10_000, settings=settings, allow_mutation=True)
    ref = reference(kind)
    rep = compare(di, ref.image, ref.batch_variance_of_mean, other=ref, tile=8)
    worst = max(float(np.abs(r.tile_z).max()) / r.tile_crit for r in rep.reports)
    print(kind, settings, f"max tile |z| / threshold {worst:.2f}")
    assert worst > 1.0


def test_the_harness_refuses_the_biased_switch():
    cfg = restir.RenderConfig(method="restir-di", frames=2, width=8, height=8,
                              settings={"temporal.previous_scene": False})
    with pytest.raises(AssertionError, match="biased switch"):
        IndependentRuns(scene("occluder"), cfg, 2)


PT_DEPTH = 3  # one indirect bounce: the replayed paths cross the moving objects and lights


@pytest.mark.parametrize("kind,camera", [(k, "none") for k in MOTION_KINDS] + [("all", "orbit")])
def test_restir_pt_with_the_replay_shift_under_motion_matches_the_path_tracer(kind, camera):
    """ReSTIR PT's defaults but the replay shift, max_depth 3, 4 spp a frame: the history's path
    and the current one each replayed in the other frame's scene."""
    pt = runs(kind, "restir-pt", 4, 10_000, camera, {"shift": "replay"}, depth=PT_DEPTH)
    ref = reference(kind, camera, PT_DEPTH)
    rep = check(pt, ref.image, ref.batch_variance_of_mean, other=ref, tile=8)
    print(kind, camera, f"MDB {rep.mdb:.4f}", pt.counters)
    assert rep.mdb < MAX_MDB


@pytest.mark.parametrize("kind", ["occluder", "light", "switch", "appear"])
def test_restir_pt_history_replayed_in_the_current_scene_is_detected(kind):
    """temporal.previous_scene=false at 1 spp a frame: the current sample replayed in the current
    scene for its density in the previous domain. Detected at tile level."""
    pt = runs(kind, "restir-pt", 1, 10_000, settings={"shift": "replay", "temporal.previous_scene": False},
              allow_mutation=True, depth=PT_DEPTH)
    ref = reference(kind, "none", PT_DEPTH)
    rep = compare(pt, ref.image, ref.batch_variance_of_mean, other=ref, tile=8)
    worst = max(float(np.abs(r.tile_z).max()) / r.tile_crit for r in rep.reports)
    print(kind, f"max tile |z| / threshold {worst:.2f}")
    assert worst > 1.0


@pytest.mark.parametrize("method,settings,fix", [
    ("restir-pt", {}, {"shift": "replay"}),
    ("restir-pt", {"shift": "reconnection"}, {"temporal": False}),
    ("suffix-restir", {}, {"prefix.temporal": False, "suffix.temporal": False})])
def test_temporal_reuse_that_cannot_follow_motion_is_refused(method, settings, fix):
    """Reconnection and hybrid shifts keep a path's suffix as cached radiance, which is not traced
    again in each frame's scene: refused, not biased, with the settings that render."""
    with pytest.raises(restir.ConfigError, match="animated"):
        restir.render(scene("all"), method=method, spp=1, frames=2, width=8, height=8, settings=settings)
    r = restir.render(scene("all"), method=method, spp=1, frames=2, width=8, height=8, keep_frames=True,
                      settings={**settings, **fix})
    assert r.frame_images.shape == (2, 8, 8, 3)


def test_validate_tests_an_animated_scene_frame_by_frame():
    """restir.validation.validate on an animated scene: each run's frames side by side, each
    against the same frame of the reference's runs (the z map is as wide as the frames)."""
    from restir.validation import validate

    cfg = restir.RenderConfig(method="restir-di", spp=1, frames=3, width=8, height=8)
    ref = restir.RenderConfig(method="pt", spp=2, frames=3, width=8, height=8, max_depth=2)
    v = validate(scene("switch"), cfg, 4, ref)
    assert v.zmap().shape[:2] == (8, 24)


def test_one_reference_measurements_refuse_an_animated_scene():
    """compare and sweep measure every frame against one image: an animated scene is refused
    there rather than measured against the wrong image."""
    from restir.compare import compare
    from restir.compare.sweep import sweep

    with pytest.raises(restir.SceneError, match="animated.*reference per frame"):
        compare(scene("occluder"), ["pt"], frames=2, width=8, height=8)
    with pytest.raises(restir.SceneError, match="animated.*reference per frame"):
        sweep(scene("occluder"), "restir-di", ["candidates=4,8"], frames=2, width=8, height=8)


def test_a_callback_that_does_not_pickle_is_refused_for_worker_processes():
    from restir.validation import validate

    moving = restir.animate(restir.load_scene("builtin:cornell-box"), callback=lambda f: {})
    cfg = restir.RenderConfig(method="pt", spp=1, frames=2, width=8, height=8)
    with pytest.raises(restir.SceneError, match="does not pickle"):
        validate(moving, cfg, 2, cfg, workers=2)
