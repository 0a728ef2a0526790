"""ReSTIR PT against exact values and against the path tracer at the same max_depth (fast tier).

Statistics: K independent runs of T frames each (restir.validation.IndependentRuns: a run's
statistic is its average image; reuse correlates pixels and frames within a run, never across
runs). Welch/t z-tests per channel at image, tile and pixel level with alpha = 1e-3 per
configuration (restir/validation/stats.py); a pass also needs the minimum detectable bias
(80% power, image level) below the bound stated per test.

- The emissive-cap sphere (A1, docs/validation.md#level-2-analytic-scenes-and-external-references):
  every non-emitting pixel has the same analytic value,
  yet distances and cosines vary from pixel to pixel; exact reference, so MDBs of 0.2-1%.
- The indirect room (light hidden from the camera and from most surfaces, glossy floor, block
  and wall): against `--method pt`, both sides noisy.
"""
import functools

import numpy as np

import pytest

import restir
from restir.scene.builtin import sphere_cap_radiance
from restir.validation import IndependentRuns
from tests.helpers import SPHERE_CAP as CAP
from tests.helpers import ANALYTIC_REL_TOL, check, paired_difference
from tests.helpers import sphere_cap as sphere



def runs(scene, settings, runs, frames, max_depth, method="restir-pt", spp=1, seed0=100, allow_mutation=False, **kw):
    cfg = restir.RenderConfig(method=method, spp=spp, frames=frames, max_depth=max_depth, settings=settings, **kw)
    out = IndependentRuns(scene, cfg, runs, seed0, allow_mutation=allow_mutation)
    if method == "restir-pt" and not allow_mutation:
        assert all(s["settings"]["debug.mutation"] == "none" for s in out.stats)  # the unbiased build, asserted
        assert not any(s["reuse_dead"] for s in out.stats), out.stats[0]["shifts"]
    return out


def check_sphere(settings, max_depth=4, k=32, frames=16, bound=0.015, allow_mutation=False):
    r = runs(sphere(), settings, k, frames, max_depth, allow_mutation=allow_mutation)
    rep = check(r, sphere_cap_radiance(CAP["albedo"], CAP["radiance"], CAP["phi"], max_depth),
                rel_tol=ANALYTIC_REL_TOL)
    print(settings, f"MDB {rep.mdb:.4f}", r.stats[0]["shifts"], r.stats[0]["final_samples"], r.stats[0].get("mcmc"))
    assert rep.mdb < bound
    return r


# (settings over the defaults: hybrid shift, direct light in the path reservoirs (direct=pt),
# temporal reuse with cap 5 + 1 spatial round with reciprocal neighbours)
SLOW = pytest.mark.slow  # kept out of the fast tier for its time budget (covered again by the slow matrix)
SPHERE = {
    "defaults": {},
    "direct-restir-di": {"direct": "restir-di"},  # the ReSTIR DI component gives the direct light
    "direct-nee": {"direct": "nee"},  # the base paths' events at the primary hit summed, not resampled
    # the image from the last pass's expected output: spatial (reciprocal, independent), temporal
    "expected": {"shade.expected": True},
    "expected-independent": ({"shade.expected": True, "spatial.reciprocal": False}, SLOW),
    "expected-temporal-nee": ({"shade.expected": True, "spatial.rounds": 0, "direct": "nee"}, SLOW),
    "canonical-1": {"temporal": False, "spatial.rounds": 0},
    "canonical-4": ({"temporal": False, "spatial.rounds": 0, "candidates": 4}, SLOW),
    "reconnection": {"shift": "reconnection", "direct": "pt"},
    "replay": {"shift": "replay", "direct": "pt"},
    "spatial-k8-rounds-3": {"temporal": False, "spatial.neighbors": 8, "spatial.rounds": 3},
    "independent": {"spatial.reciprocal": False},  # the independent neighbours of the official ReSTIR PT
    "reciprocal-k8-rounds-3": ({"temporal": False, "spatial.neighbors": 8, "spatial.rounds": 3,
                                "spatial.reciprocal": True}, SLOW),
    "temporal-no-cap": ({"temporal.cap": 0.0, "spatial.rounds": 0}, SLOW),
    "mcmc-z": {"mcmc.steps": 2},
    "mcmc-rc-prev": {"mcmc.steps": 2, "mcmc.start": "rc_prev"},
}


@pytest.mark.parametrize("config", [pytest.param(k, marks=v[1]) if isinstance(v, tuple) else k
                                    for k, v in SPHERE.items()])
def test_emissive_cap_sphere_is_exact(config):
    c = SPHERE[config]
    check_sphere(c[0] if isinstance(c, tuple) else c)


@pytest.mark.slow
@pytest.mark.parametrize("max_depth", [3, 6])
def test_emissive_cap_sphere_other_depths(max_depth):
    check_sphere({"spatial.neighbors": 4}, max_depth=max_depth)


@pytest.mark.parametrize("method", ["restir-pt", "suffix-restir"])
def test_deep_paths_past_the_unbounded_cap(method):
    """Path lengths are 8-bit fields, so max_depth goes to 255 (Bitterli's scenes ask for 65), while
    -1 renders as 64. A furnace of albedo 0.99 (L = 1 - 0.99^D with radiance 0.01): 0.866 at
    max_depth 200 and 0.474 at 64, so a method that cut its paths (or wrapped a length) at 64,
    128 or 256 reads far off; the reuse (temporal, spatial, the shifts) runs on those paths.
    One run of 4 frames at 8x8 (every path a pixel's is the same value up to the light's
    sampling; measured spread of the image mean under 1%)."""
    scene = restir.load_scene("builtin:furnace", width=8, height=8, albedo=0.99, radiance=0.01, max_depth=200)
    r = restir.render(scene, method=method, spp=1, frames=4, max_depth=200)
    assert float(r.image.mean()) == pytest.approx(1 - 0.99 ** 200, rel=0.02)
    with pytest.raises(restir.config.ConfigError, match="up to 255"):
        restir.render(scene, method=method, spp=1, frames=1, max_depth=256)


def indirect_room(size=16):
    return restir.load_scene("builtin:indirect-room", width=size, height=size)


@functools.lru_cache(maxsize=None)
def room_reference(max_depth):
    return runs(indirect_room(), {}, 64, 16, max_depth, method="pt", spp=4, seed0=5000)


# The room's sharp rough-plastic coat and glossy floor make path contributions heavy-tailed:
# at this cost the MDB is 5-6%, so these run in the slow tier (with the full matrix,
# test_restir_pt_matrix.py); the sphere above carries the fast tier's power.
ROOM = {
    "canonical": {"temporal": False, "spatial.rounds": 0},
    "spatial-reconnection-k8": {"temporal": False, "shift": "reconnection", "spatial.neighbors": 8},
    "defaults": {},
}


@pytest.mark.slow
@pytest.mark.parametrize("config", list(ROOM))
def test_indirect_room_matches_path_tracing(config):
    ref = room_reference(5)
    r = runs(indirect_room(), ROOM[config], 64, 16, 5)
    rep = check(r, ref.image, ref.batch_variance_of_mean, other=ref, tile=4)
    print(config, f"MDB {rep.mdb:.4f}", r.stats[0]["shifts"], r.stats[0]["final_samples"])
    assert rep.mdb < 0.06


# Power checks (docs/validation.md#power-checks-the-mutation-table) on the estimator: each mutant
# fails the test its unbiased build
# passes. (The shift mutants are caught by tests/unit/test_pt_shifts.py and
# test_pt_shift_integrals.py, BSDF-twice among them; here it runs in the slow tier.)
@pytest.mark.parametrize("mutation", ["m_per_event", pytest.param("bsdf_twice", marks=SLOW)])
def test_estimator_mutations_are_caught_on_the_sphere(mutation):
    with pytest.raises(AssertionError):
        check_sphere({"debug.mutation": mutation, "direct": "pt"}, allow_mutation=True)


@SLOW  # its own kernel build; in the fast tier test_expected_output_changes_only_the_colour fails this mutant too
def test_expected_output_not_normalized_is_caught():
    """shade.expected whose spatial pass does not divide its expected output by V + 1 (the
    `expected_unnormalized` mutation: the pixels the pass resampled too bright) fails the sphere
    that shade.expected passes."""
    with pytest.raises(AssertionError):
        check_sphere({"debug.mutation": "expected_unnormalized", "shade.expected": True}, allow_mutation=True)


@pytest.mark.parametrize("settings", [{}, {"spatial.rounds": 0}, {"spatial.reciprocal": False, "direct": "nee"}])
def test_expected_output_changes_only_the_colour(settings):
    """shade.expected replaces the selected sample F(Y) W by the last pass's expectation over its
    inputs, sum_i w_i F(y_i) / p_hat(y_i) / normalization. With p_hat the luminance, each term's
    luminance is w_i, so every pixel keeps its luminance (w_sum / normalization) exactly while its
    colour changes; the reservoirs do not see the image, so the shifts and final samples are those
    of the run without it, frame after frame. (The `expected_unnormalized` mutant fails the
    luminance check: its image mean measured 7.5% brighter at these settings.)"""
    scene = restir.load_scene("builtin:cornell-box-glossy", width=24, height=20)
    out = {}
    for expected in (False, True):
        cfg = restir.RenderConfig(method="restir-pt", spp=1, frames=4, seed=9, max_depth=5, keep_frames=True,
                                  settings={**settings, "shade.expected": expected})
        out[expected] = restir.render(scene, cfg)
    lum = np.array([0.2126, 0.7152, 0.0722])
    a, b = (np.asarray(out[e].frame_images, np.float64) for e in (False, True))
    assert np.allclose(a @ lum, b @ lum, rtol=1e-4, atol=1e-6)
    assert np.abs(a - b).max() > 1e-2  # the colours did change
    assert out[False].stats["shifts"] == out[True].stats["shifts"]
    assert out[False].stats["final_samples"] == out[True].stats["final_samples"]


def test_direct_light_counted_twice_is_caught():
    """direct=nee's trace stage resampling the events at x_0 as well as summing them (the
    `nee_also_resampled` mutation) fails the sphere that direct=nee passes (SPHERE above)."""
    with pytest.raises(AssertionError):
        check_sphere({"debug.mutation": "nee_also_resampled", "direct": "nee"}, allow_mutation=True)


@pytest.mark.parametrize("reciprocal", [False, True])
def test_dropping_failed_shifts_is_caught(reciprocal):
    """Neighbours whose shift failed left out of V and of the canonical weight (defect A3's
    analogue): about 18% bright in the indirect room with 8 neighbours in a 2 px disk; in both
    spatial kernels. (With the default disk, 20 px, most neighbours of this 16-pixel image fall off
    screen instead of failing their shift, and the defect brightens by 1.5%: not a test of it.)"""
    ref = room_reference(3)
    settings = {"temporal": False, "spatial.neighbors": 8, "spatial.radius": 2.0, "direct": "pt",
                "spatial.reciprocal": reciprocal}
    r = runs(indirect_room(), settings, 64, 16, 3)
    check(r, ref.image, ref.batch_variance_of_mean, other=ref, tile=4)
    m = runs(indirect_room(), {**settings, "debug.mutation": "drop_failed_shifts"}, 64, 16, 3, allow_mutation=True)
    with pytest.raises(AssertionError):
        check(m, ref.image, ref.batch_variance_of_mean, other=ref, tile=4)


# MCMC suffix mutations (mcmc.steps, restir_pt/s3_mcmc.py) must change nothing on average: each
# configuration with mutations against the same configuration and seeds without them, run by run
# (tests/helpers.paired_difference), 64 runs x 16 frames at 16x16, max_depth 4: the sphere above
# has one value everywhere, so its mutations barely move anything; these two scenes have colour,
# glossy lobes and 40-75% accepted proposals.
MCMC_SCENES = ["builtin:cornell-box-glossy", "builtin:indirect-room"]
MCMC_BASES = {"defaults": {}, "direct-restir-di": {"direct": "restir-di"},
              "spatial-k8-rounds-2": {"direct": "pt", "temporal": False, "spatial.neighbors": 8, "spatial.rounds": 2}}


def mcmc_paired(scene_spec, base, extra, allow_mutation=False):
    scene = restir.load_scene(scene_spec, width=16, height=16)
    b = runs(scene, base, 64, 16, 4)
    a = runs(scene, {**base, **extra}, 64, 16, 4, allow_mutation=allow_mutation)
    print(scene_spec, base, extra, a.stats[0]["mcmc"])
    return check(paired_difference(a, b), b.image, tile=4)


@pytest.mark.parametrize("start", ["z", "rc_prev"])
@pytest.mark.parametrize("base", [pytest.param(k, marks=SLOW) if k == "direct-restir-di" else k for k in MCMC_BASES])
@pytest.mark.parametrize("scene", MCMC_SCENES)
def test_mcmc_mutations_change_nothing_on_average(scene, base, start):
    rep = mcmc_paired(scene, MCMC_BASES[base], {"mcmc.steps": 2, "mcmc.start": start})
    assert rep.mdb < 0.02


@pytest.mark.parametrize("scene", MCMC_SCENES)
def test_mcmc_without_the_weight_update_is_caught(scene):
    """W kept on acceptance: accepted proposals are the brighter ones, so the image brightens
    (measured 3.5-14% here)."""
    with pytest.raises(AssertionError):
        mcmc_paired(scene, MCMC_BASES["spatial-k8-rounds-2"], {"mcmc.steps": 2, "debug.mutation": "mcmc_keep_w"},
                    allow_mutation=True)


# Reciprocal neighbours (spatial.reciprocal) change which pixels are reused, not the estimator: the
# same configurations and seeds with independent neighbours, run by run
# (docs/validation.md#level-4-invariance-tests). The
# glossy box's paired difference resolves 0.5-0.7% (64 runs); the room's is heavy-tailed (1.9% at
# 192 runs), so it runs in the slow tier.
@pytest.mark.parametrize("base", ["defaults", "spatial-k8-rounds-2"])
@pytest.mark.parametrize("scene, K, bound", [("builtin:cornell-box-glossy", 64, 0.01),
                                             pytest.param("builtin:indirect-room", 192, 0.025, marks=SLOW)])
def test_reciprocal_neighbours_change_nothing_on_average(scene, K, bound, base):
    s = restir.load_scene(scene, width=16, height=16)
    b = runs(s, {**MCMC_BASES[base], "spatial.reciprocal": False}, K, 16, 4)
    a = runs(s, {**MCMC_BASES[base], "spatial.reciprocal": True}, K, 16, 4)
    rep = check(paired_difference(a, b), b.image, tile=4)
    print(scene, base, f"MDB {rep.mdb:.4f}", a.stats[0]["shifts"], b.stats[0]["shifts"])
    assert rep.mdb < bound


def test_harness_refuses_mutations():
    with pytest.raises(AssertionError, match="fault injection"):
        runs(sphere(), {"debug.mutation": "bsdf_twice"}, 2, 1, 4)


@pytest.mark.parametrize("settings", [{}, {"direct": "restir-di"}, {"direct": "nee"},
                                      {"mcmc.steps": 1, "spatial.rounds": 2}, {"shade.expected": True},
                                      {"shade.expected": True, "spatial.rounds": 0}])
def test_fused_trace_and_temporal_is_the_split_pipeline_bit_for_bit(settings):
    """The shipped pipeline runs trace + initial RIS and temporal reuse as one kernel, and every
    pass after it writes into the history's buffer; stages.split runs the two stages apart with a
    third reservoir buffer. The same functions in the same order: the images, the shift and event
    counts must be identical bit for bit over frames (temporal reuse from the second sample on),
    and the fused pipeline must hold one path-reservoir buffer fewer."""
    scene = restir.load_scene("builtin:cornell-box-glossy", width=24, height=20)
    out = {}
    for split in (False, True):
        cfg = restir.RenderConfig(method="restir-pt", spp=2, frames=3, seed=5, max_depth=5,
                                  settings={**settings, "stages.split": split})
        out[split] = restir.render(scene, cfg)
    fused, split = out[False], out[True]
    assert np.array_equal(fused.image, split.image)
    assert fused.stats["shifts"] == split.stats["shifts"] and fused.stats["shifts"]["temporal"]["reconnection"]["tried"]
    assert fused.stats["counters"] == split.stats["counters"]
    assert fused.stats["final_samples"] == split.stats["final_samples"]
    assert sum(fused.stats["rays_by_stage"].values()) == sum(split.stats["rays_by_stage"].values())
    bpp_f, bpp_s = fused.stats["bytes_per_pixel"], split.stats["bytes_per_pixel"]
    assert "reservoirs_pass" not in bpp_f and bpp_s["reservoirs_pass"] == 76
    assert bpp_s["total"] - bpp_f["total"] == 76
    assert fused.stats["stages"]["trace_temporal"]["calls"] == 6 and split.stats["stages"]["temporal"]["calls"] == 5


def test_memory_per_pixel():
    """The memory target, 256 B per pixel with the film's accumulation not counted, met by
    the defaults (direct=pt: direct light in the path reservoirs; the primary rays rebuilt from the
    camera position; emission.adaptive's records and marks, 17 B: 237 B); with the ReSTIR DI
    component (direct=restir-di) 297 B; with direct=nee 249 B (the trace stage's direct light, 12
    B); with shade.expected 249 B (the expected output). The registry counts every buffer a method
    allocates, so a buffer added anywhere moves these numbers."""
    scene = restir.load_scene("builtin:cornell-box", width=8, height=8)
    for settings, expected in (({}, 237), ({"direct": "restir-di"}, 297), ({"direct": "nee"}, 249),
                               ({"shade.expected": True}, 249)):
        res = restir.render(scene, restir.RenderConfig(method="restir-pt", spp=2, settings=settings))
        bpp = res.stats["bytes_per_pixel"]
        assert bpp["total"] - bpp["film_mean"] - bpp["film_m2"] == expected, bpp
        assert bpp["events"] == 8 and bpp["shift_events"] == 8


def test_split_stages_refuse_fault_injections():
    scene = restir.load_scene("builtin:cornell-box", width=8, height=8)
    cfg = restir.RenderConfig(method="restir-pt", settings={"stages.split": True, "debug.mutation": "m_per_event"})
    with pytest.raises(restir.ConfigError, match="stages.split"):
        restir.render(scene, cfg)


def test_option_combinations_refused_before_rendering():
    """shade.expected needs a resampling pass last (an MCMC pass last has no expectation built);
    direct=nee is ReSTIR PT's (Suffix ReSTIR's prefixes already sum their own light)."""
    scene = restir.load_scene("builtin:cornell-box", width=8, height=8)
    with pytest.raises(restir.ConfigError, match="shade.expected needs"):
        restir.render(scene, restir.RenderConfig(method="restir-pt", settings={
            "shade.expected": True, "mcmc.steps": 1, "spatial.rounds": 0}))
    with pytest.raises(restir.ConfigError, match="direct must be restir-di or pt"):
        restir.render(scene, restir.RenderConfig(method="suffix-restir", settings={"direct": "nee"}))
