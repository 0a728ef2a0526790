"""Slow tier: the ReSTIR DI stage-isolation matrix (docs/validation.md#level-3-stage-matrix, C1-C4)
against the
direct-only path tracer, with independent runs on both sides.

Every configuration runs K = 64 independent runs (fresh seed and history each) of T = 8 frames
at 32x32; its statistic per run is the run's average image. The reference is the path tracer
(max_depth 2, MIS) over 64 independent runs x 8 frames x 16 spp, rendered once per scene and
camera motion. Welch z
per channel at image, tile (8x8) and pixel level, alpha = 1e-3 per configuration
(restir/validation/stats.py); the MDB (80% power, image level) is printed and bounded.

Scenes: the feature scene (environment map, textures, glossy and rough-glass materials), the
half-dark scene (about half of all light candidates are zero: C6, the target of defects A1 and
A3), the shadow scene (a large light behind blinds: visibility differs from pixel to pixel) and
the glossy Cornell box (GGX and Beckmann surfaces under a small light); the bump-map scene
(tests/data/feature_scene.py) with the cells of BUMP_CELLS; and the delta-light and thin-lens
scenes (tests/helpers.py LIGHT_MATRIX_SCENES: samples on point, spot and directional lights, mixed
with an area light and an environment or alone; primary hits through a thin lens) with the same cells.
"""
import functools
import tempfile

import pytest

import restir
from restir.validation import IndependentRuns
from tests.helpers import MATRIX_CAMERAS, check
from tests.helpers import LIGHT_MATRIX_SCENES, MATERIAL_MATRIX_SCENES
from tests.scenes import bump_scene, feature_scene_named, half_dark_scene, mask_scene, shadow_scene

RUNS, FRAMES, SIZE = 64, 8, 32

NO_REUSE = {"temporal": False, "spatial.rounds": 0}
SPATIAL_ONLY = {"temporal": False}
TEMPORAL_ONLY = {"spatial.rounds": 0}

# name: (settings over the defaults, camera motion)
MATRIX = {
    # C0/C1: initial RIS alone, light candidates M in {1, 4, 32}, with and without BSDF candidates
    "C1-light-1": ({**NO_REUSE, "candidates": 1, "candidates.bsdf": 0, "visibility": "shading"}, "none"),
    "C1-light-4": ({**NO_REUSE, "candidates": 4, "candidates.bsdf": 0}, "none"),
    "C1-light-32-bsdf-1": ({**NO_REUSE}, "none"),
    # C2: temporal only, confidence caps {1, 5, 20, none}
    "C2-cap-1": ({**TEMPORAL_ONLY, "temporal.cap": 1.0}, "none"),
    "C2-cap-5": ({**TEMPORAL_ONLY, "temporal.cap": 5.0}, "none"),
    "C2-cap-20": ({**TEMPORAL_ONLY, "temporal.cap": 20.0}, "none"),
    "C2-no-cap": ({**TEMPORAL_ONLY, "temporal.cap": 0.0}, "none"),
    # C3: spatial only, k in {1, 2, 4, 8}, 1-3 rounds; and unshadowed targets
    "C3-k1": ({**SPATIAL_ONLY, "spatial.neighbors": 1, "spatial.rounds": 1}, "none"),
    "C3-k2": ({**SPATIAL_ONLY, "spatial.neighbors": 2, "spatial.rounds": 1}, "none"),
    "C3-k4-rounds-3": ({**SPATIAL_ONLY, "spatial.neighbors": 4, "spatial.rounds": 3}, "none"),
    "C3-k8": ({**SPATIAL_ONLY, "spatial.neighbors": 8, "spatial.rounds": 1}, "none"),
    "C3-k3-rounds-2-unshadowed": ({**SPATIAL_ONLY, "spatial.rounds": 2, "visibility": "shading",
                                   "candidates.bsdf": 0}, "none"),
    # C4: temporal + spatial (the defaults), unshadowed, and with a moving camera
    "C4-defaults": ({}, "none"),
    "C4-unshadowed": ({"visibility": "shading", "candidates.bsdf": 0}, "none"),
    "C4-k8-radius-10": ({"spatial.neighbors": 8, "spatial.radius": 10.0}, "none"),
    "C4-orbit": ({}, "orbit"),
    "C4-dolly": ({}, "dolly"),
    "C4-centre": ({}, "centre"),  # pixel-centre primary rays: every frame the same primary hit
}
SCENES = ["features", "half-dark", "shadow", "cornell-box-glossy"]
# Per scene: settings under every configuration's own (half-dark keeps one light candidate, so
# that about half of the canonical samples are zero), and ReSTIR DI's spp per frame (in the
# Cornell box the pixels on the edge of its small, bright light dominate the variance).
SCENE_SETTINGS = {"half-dark": {"candidates": 1}}
SCENE_SPP = {"cornell-box-glossy": 4}
# The sun alone at max_depth 2: ReSTIR DI's estimate is the path tracer's at every pixel away from a
# shadow's edge (the one light is chosen with probability 1; measured: the two agree to 4e-7 per
# pixel with the same camera samples), so most tiles have next to no variance and float32 sums
# differ there by about 1e-5: deviations below 1e-4 relative count as zero, as in the Mitsuba tests.
SCENE_REL_TOL = {"sun": 1e-4}


@functools.lru_cache(maxsize=None)
def scene(name):
    if name == "half-dark":
        return half_dark_scene()
    if name == "shadow":
        return shadow_scene()
    if name == "bumps":
        return bump_scene()
    if name == "masks":
        return mask_scene()
    if name == "features":
        from tests.data.feature_scene import write_feature_scene

        return restir.load_scene(write_feature_scene(tempfile.mkdtemp()))
    if name in LIGHT_MATRIX_SCENES + MATERIAL_MATRIX_SCENES:
        return feature_scene_named(name)
    return restir.load_scene(f"builtin:{name}")


def runs(name, method, spp, seed0, motion="none", settings=None):
    motion, speed, jitter = MATRIX_CAMERAS[motion]
    cfg = restir.RenderConfig(method=method, spp=spp, frames=FRAMES, width=SIZE, height=SIZE, max_depth=2,
                              camera_motion=motion, camera_speed=speed, jitter=jitter, settings=settings or {})
    return IndependentRuns(scene(name), cfg, RUNS, seed0)


@functools.lru_cache(maxsize=None)
def reference(name, motion):
    return runs(name, "pt", 16, 500_000, motion)


@pytest.mark.slow
@pytest.mark.parametrize("config", list(MATRIX))
@pytest.mark.parametrize("name", SCENES)
def test_restir_di_matrix(name, config):
    settings, motion = MATRIX[config]
    settings = {**SCENE_SETTINGS.get(name, {}), **settings}
    di = runs(name, "restir-di", SCENE_SPP.get(name, 1), 10_000, motion, settings)
    ref = reference(name, motion)
    print(name, config, settings, f"K={RUNS} T={FRAMES} {SIZE}x{SIZE}", "counters", di.counters)
    rep = check(di, ref.image, ref.batch_variance_of_mean, other=ref, tile=8, rel_tol=SCENE_REL_TOL.get(name, 0.0))
    assert rep.mdb < 0.08


# on the bump-map and the mask scenes (tests/data/feature_scene.py): candidates alone, each reuse, unshadowed
# targets, the defaults and a moving camera
BUMP_CELLS = ["C1-light-32-bsdf-1", "C2-cap-20", "C3-k4-rounds-3", "C4-defaults", "C4-unshadowed", "C4-orbit"]


@pytest.mark.slow
@pytest.mark.parametrize("config", BUMP_CELLS)
@pytest.mark.parametrize("name", ["bumps", "masks"])
def test_restir_di_matrix_on_bump_maps_and_masks(name, config):
    test_restir_di_matrix(name, config)


@pytest.mark.slow
@pytest.mark.parametrize("config", BUMP_CELLS)
@pytest.mark.parametrize("name", LIGHT_MATRIX_SCENES + MATERIAL_MATRIX_SCENES)
def test_restir_di_matrix_on_delta_lights_and_a_lens(name, config):
    test_restir_di_matrix(name, config)


# Scenes in motion (tests/scenes.py motion_scene: a sliding block, a moving light, a light switched
# off and on, a block that vanishes and comes back, all four), each with a still and an orbiting
# camera: temporal reuse alone (cap 20), the defaults, unshadowed targets. Each run's statistic is
# its 8 frames side by side, each frame against the path tracer's runs of the same frame; ReSTIR
# DI at 4 spp a frame (tests/integration/test_motion.py says why).
MOTION_CELLS = ["C2-cap-20", "C4-defaults", "C4-unshadowed"]


@functools.lru_cache(maxsize=None)
def motion_reference(kind, motion):
    return motion_runs(kind, "pt", 16, 500_000, motion)


def motion_runs(kind, method, spp, seed0, motion, settings=None):
    camera, speed, jitter = MATRIX_CAMERAS[motion]
    cfg = restir.RenderConfig(method=method, spp=spp, frames=FRAMES, width=SIZE, height=SIZE, max_depth=2,
                              camera_motion=camera, camera_speed=speed, jitter=jitter, settings=settings or {})
    return IndependentRuns(_motion_scene(kind), cfg, RUNS, seed0, per_frame=True)


@functools.lru_cache(maxsize=None)
def _motion_scene(kind):
    from tests.scenes import motion_scene

    return motion_scene(kind)


@pytest.mark.slow
@pytest.mark.parametrize("config", MOTION_CELLS)
@pytest.mark.parametrize("motion", ["none", "orbit"])
@pytest.mark.parametrize("kind", ["occluder", "light", "switch", "appear", "all"])
def test_restir_di_matrix_in_motion(kind, motion, config):
    settings, _ = MATRIX[config]
    di = motion_runs(kind, "restir-di", 4, 10_000, motion, settings)
    ref = motion_reference(kind, motion)
    print(kind, motion, config, settings, f"K={RUNS} T={FRAMES} {SIZE}x{SIZE} per frame", "counters", di.counters)
    rep = check(di, ref.image, ref.batch_variance_of_mean, other=ref, tile=8)
    assert rep.mdb < 0.08
