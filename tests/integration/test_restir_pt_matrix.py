"""Slow tier: the ReSTIR PT stage-isolation matrix (docs/validation.md#level-3-stage-matrix) against
the path tracer at
the same max_depth, with independent runs on both sides (restir.validation.IndependentRuns).

Every configuration: K independent runs of T frames at 32x32, its statistic per run the run's
average image; the reference is the path tracer over K runs x T frames x 16 spp, rendered once
per scene and camera motion (48 spp on veach-mis). K x T per scene: 64 x 8 where that bounds the minimum detectable
bias (MDB) at a few percent (64 x 16 in the indirect room, whose direct=pt cell measured 6.5% at
64 x 8); veach-bidir 128 x 32 and veach-mis 384 x 32, whose caustic paths
(through the glass egg; off the glossy plates into the small bright lights) make a run's image
mean heavy-tailed (measured: at 64 x 8 their MDB was 16% and 27%). Welch z per channel at image,
tile (8x8) and pixel level, alpha = 1e-3 per configuration; the MDB (80% power, image level) is
printed and bounded per scene (the emissive-cap sphere has an exact reference instead).

Scenes: the glossy Cornell box, veach-bidir and veach-mis (shared scenes), the emissive-cap
sphere (A1) and the indirect room (light hidden from the camera, glossy surfaces); the bump-map
scene (tests/data/feature_scene.py) with the cells of BUMP_CELLS; and the delta-light and thin-lens
scenes (tests/data/feature_scene.py: point, spot and directional lights mixed with an area light
and an environment, the points and spots alone, the sun alone, a thin lens) with LIGHT_CELLS.
"""

import functools

import pytest

from tests.helpers import FULL_MATRIX_SCENES, LIGHT_MATRIX_SCENES, MATERIAL_MATRIX_SCENES, PARTIAL_MATRIX_SCENES, run_cell

NO_REUSE = {"temporal": False, "spatial.rounds": 0}
SPATIAL = {"temporal": False}
TEMPORAL = {"spatial.rounds": 0}
# The defaults until 2026-12-06 (the official ones, with independent neighbours): every cell but
# the defaults' own keeps them, so the verdicts in
# docs/validation.md#results-restir-pt-stages-and-options stay those of the configuration
# each cell ran.
OFFICIAL = {"direct": "restir-di", "temporal.cap": 20.0, "spatial.reciprocal": False, "emission.rays": 1}
# The emission seen directly from one camera ray a sample, the default until emission.rays became
# 4 (2026-12-07): the cells recorded before then keep it; C4-defaults, -orbit, -dolly and -centre
# take the defaults as they are.
ONE_RAY = {"emission.rays": 1}
# The extra camera rays at every pixel, as until emission.adaptive became the default (2026-12-07,
# later that day): the cells that tested emission.rays before keep it.
EVERY_PIXEL = {"emission.adaptive": False}

MATRIX = {
    "C1-candidates-1": ({**OFFICIAL, **NO_REUSE}, "none"),
    "C1-candidates-4": ({**OFFICIAL, **NO_REUSE, "candidates": 4}, "none"),
    **{f"C3-{shift}-k{k}": ({**OFFICIAL, **SPATIAL, "shift": shift, "spatial.neighbors": k}, "none")
       for shift in ("hybrid", "reconnection", "replay") for k in (1, 3, 8)},
    **{f"C3-{shift}-k3-rounds-{r}": ({**OFFICIAL, **SPATIAL, "shift": shift, "spatial.rounds": r}, "none")
       for shift in ("hybrid", "reconnection", "replay") for r in (2, 3)},
    "C2-cap-1": ({**OFFICIAL, **TEMPORAL, "temporal.cap": 1.0}, "none"),
    "C2-cap-20": ({**OFFICIAL, **TEMPORAL, "temporal.cap": 20.0}, "none"),
    "C2-no-cap": ({**OFFICIAL, **TEMPORAL, "temporal.cap": 0.0}, "none"),
    # the defaults (direct=pt, temporal.cap=5, since 2026-12-06) with every stage on, still and moving
    "C4-defaults": ({}, "none"),
    "C4-orbit": ({}, "orbit"),
    "C4-dolly": ({}, "dolly"),
    "C4-centre": ({}, "centre"),  # pixel-centre primary rays: every frame the same primary hit
    "C4-official": ({**OFFICIAL}, "none"),  # the defaults until 2026-12-06 (cell C4-defaults then)
    "C4-cap-5": ({**OFFICIAL, "temporal.cap": 5.0}, "none"),
    "C4-direct-pt": ({**OFFICIAL, "direct": "pt"}, "none"),
    # direct=nee: the base paths' events at x_0 summed, resampling from x_1 (every stage on)
    "C4-direct-nee": ({"direct": "nee", **ONE_RAY}, "none"),
    "C4-direct-nee-orbit": ({"direct": "nee", **ONE_RAY}, "orbit"),
    # shade.expected: the image from the last pass's expected output (spatial, temporal)
    "C4-expected": ({"shade.expected": True, **ONE_RAY}, "none"),
    "C4-expected-nee-orbit": ({"shade.expected": True, "direct": "nee", **ONE_RAY}, "orbit"),
    "C2-expected-nee": ({"shade.expected": True, "direct": "nee", **TEMPORAL, **ONE_RAY}, "none"),
    # emission.rays 4 (the default) at every pixel, with both options above, orbiting
    "C4-emission-rays-orbit": ({"emission.rays": 4, "shade.expected": True, "direct": "nee", **EVERY_PIXEL},
                               "orbit"),
    "C4-k8-rounds-2": ({**OFFICIAL, "spatial.neighbors": 8, "spatial.rounds": 2}, "none"),
    # reciprocal neighbours (spatial.reciprocal, the default): the pass on its own, several rounds
    "C3-reciprocal-k3": ({**OFFICIAL, **SPATIAL, "spatial.reciprocal": True}, "none"),
    "C3-reciprocal-k8-rounds-2": ({**OFFICIAL, **SPATIAL, "spatial.reciprocal": True, "spatial.neighbors": 8,
                                   "spatial.rounds": 2}, "none"),
    # the defaults with independent neighbours (the defaults before reciprocal ones; cells
    # C4-defaults and -orbit until then)
    "C4-independent": ({"spatial.reciprocal": False, **ONE_RAY}, "none"),
    "C4-independent-orbit": ({"spatial.reciprocal": False, **ONE_RAY}, "orbit"),
    # MCMC suffix mutations between temporal and spatial reuse (s3_mcmc.py)
    "C6-mcmc-z": ({**OFFICIAL, "mcmc.steps": 2}, "none"),
    "C6-mcmc-rc-prev": ({**OFFICIAL, "mcmc.steps": 2, "mcmc.start": "rc_prev"}, "none"),
    "C6-mcmc-rc-prev-spatial": ({**OFFICIAL, **SPATIAL, "mcmc.steps": 4, "mcmc.start": "rc_prev"}, "none"),
    "C6-mcmc-orbit": ({**OFFICIAL, "mcmc.steps": 1, "mcmc.start": "rc_prev"}, "orbit"),
}


# on the bump-map and the mask scenes (shifts across tilted frames and null lobes): every shift, spatial rounds, temporal reuse, the defaults and a moving camera
BUMP_CELLS = ["C1-candidates-1", "C3-hybrid-k3", "C3-reconnection-k3", "C3-replay-k3", "C3-hybrid-k3-rounds-2",
              "C2-cap-20", "C4-defaults", "C4-orbit", "C4-official"]


@pytest.mark.slow
@pytest.mark.parametrize("config", list(MATRIX))
@pytest.mark.parametrize("name", FULL_MATRIX_SCENES)
def test_restir_pt_matrix(name, config):
    settings, motion = MATRIX[config]
    print(config, end=" ")
    run_cell(name, "restir-pt", settings, motion, config)


@pytest.mark.slow
@pytest.mark.parametrize("config", BUMP_CELLS)
@pytest.mark.parametrize("name", PARTIAL_MATRIX_SCENES)
def test_restir_pt_matrix_on_bump_maps_and_masks(name, config):
    settings, motion = MATRIX[config]
    print(config, end=" ")
    run_cell(name, "restir-pt", settings, motion, config)


# on the delta-light and thin-lens scenes: candidates alone, every shift, temporal reuse, the defaults
# still and moving, and MCMC suffix mutations (a fresh light sample at z may change the light's kind)
LIGHT_CELLS = ["C1-candidates-1", "C3-hybrid-k3", "C3-reconnection-k3", "C3-replay-k3", "C2-cap-20", "C4-defaults",
               "C4-orbit", "C6-mcmc-z"]


@pytest.mark.slow
@pytest.mark.parametrize("config", LIGHT_CELLS)
@pytest.mark.parametrize("name", LIGHT_MATRIX_SCENES + MATERIAL_MATRIX_SCENES)
def test_restir_pt_matrix_on_delta_lights_and_a_lens(name, config):
    settings, motion = MATRIX[config]
    print(config, end=" ")
    run_cell(name, "restir-pt", settings, motion, config)


# Scenes in motion (tests/scenes.py motion_scene; docs/validation.md#scenes-in-motion), each with a
# still and an orbiting camera: temporal reuse alone (cap 20) and the defaults, both with the
# replay shift (the shift that traces a path whole in each frame's scene; the others are refused
# on an animated scene), and the official direct light (direct=restir-di: its ReSTIR DI component
# reuses in motion too). 64 runs x 8 frames at 32x32, max_depth 3, 4 spp a frame, each run's
# frames side by side against the path tracer's (16 spp) of the same frames.
MOTION_CELLS = {
    "C2-replay-cap-20": {**TEMPORAL, "shift": "replay", "temporal.cap": 20.0},
    "C4-replay": {"shift": "replay"},
    "C4-replay-direct-restir-di": {"shift": "replay", "direct": "restir-di"},
}


def _motion_runs(kind, method, spp, seed0, motion, settings=None):
    import restir
    from restir.validation import IndependentRuns
    from tests.helpers import MATRIX_CAMERAS
    from tests.scenes import motion_scene

    camera, speed, jitter = MATRIX_CAMERAS[motion]
    cfg = restir.RenderConfig(method=method, spp=spp, frames=8, width=32, height=32, max_depth=3,
                              camera_motion=camera, camera_speed=speed, jitter=jitter, settings=settings or {})
    return IndependentRuns(_motion_scene(kind), cfg, 64, seed0, per_frame=True)


@functools.lru_cache(maxsize=None)
def _motion_scene(kind):
    from tests.scenes import motion_scene

    return motion_scene(kind)


@functools.lru_cache(maxsize=None)
def _motion_reference(kind, motion):
    return _motion_runs(kind, "pt", 16, 500_000, motion)


@pytest.mark.slow
@pytest.mark.parametrize("config", list(MOTION_CELLS))
@pytest.mark.parametrize("motion", ["none", "orbit"])
@pytest.mark.parametrize("kind", ["occluder", "light", "switch", "appear", "all"])
def test_restir_pt_matrix_in_motion(kind, motion, config):
    from tests.helpers import check

    r = _motion_runs(kind, "restir-pt", 4, 10_000, motion, MOTION_CELLS[config])
    ref = _motion_reference(kind, motion)
    print(kind, motion, config, "counters", r.counters)
    rep = check(r, ref.image, ref.batch_variance_of_mean, other=ref, tile=8)
    assert rep.mdb < 0.06
