"""ReSTIR DI against the direct-only path tracer (`--method pt --max-depth 2`), per pixel.

Both sides noisy: Welch z per channel over 32 frames (batch means), alpha = 1e-3 per
configuration, image/tile/pixel levels as restir/validation/stats.py; the MDB is asserted small.
Configurations cover initial RIS (light and BSDF candidates), visibility, temporal and spatial reuse.
"""
import numpy as np
import pytest

import restir
from tests.helpers import check, check_no_trend, long_run_trend
from tests.scenes import half_dark_scene, shadow_scene

FRAMES = 32


def scene_for(name, tmp_path):
    if name == "half-dark":
        return half_dark_scene()
    if name == "shadow":
        return shadow_scene()
    if name == "features":
        from tests.data.feature_scene import write_feature_scene

        return restir.load_scene(write_feature_scene(str(tmp_path)))
    return restir.load_scene(f"builtin:{name}")


def render(scene, method, spp, seed, size=24, **settings):
    cfg = restir.RenderConfig(method=method, spp=spp, frames=FRAMES, width=size, height=size, seed=seed,
                              max_depth=2, settings=settings, keep_frames=True)
    r = restir.render(scene, cfg)
    if method == "restir-di" and "debug.mutation" not in settings:
        assert r.stats["settings"]["debug.mutation"] == "none"  # the unbiased build, asserted
    assert not any(n for name, n in r.stats["counters"].items() if name.startswith("nonfinite")), r.stats["counters"]
    return r


# (DI spp, PT spp, MDB bound): in the Cornell boxes the pixels on the edge of the small, bright
# light dominate the image-level variance of both sides.
SAMPLES = {"cornell-box": (32, 128, 0.065), "cornell-box-glossy": (32, 128, 0.065), "features": (8, 32, 0.03),
           "half-dark": (8, 32, 0.03), "shadow": (8, 32, 0.03)}


# (light candidates, BSDF candidates, visibility): light-only, BSDF-only and both generators;
# visibility traced at shading or by the visibility stage.
# BSDF candidates alone cannot find small lights (Cornell boxes, half-dark) often enough for a
# per-pixel test at these sample counts (unbiased but heavy-tailed: the skew guard and the tail
# fraction fire), so that row runs on the scenes lit by an environment or a large light.
CANDIDATES = [(1, 0, "shading"), (4, 0, "reuse"), (32, 0, "shading"), (0, 1, "reuse"), (4, 1, "reuse"),
              (4, 2, "shading")]
CANONICAL = [(name, *c) for name in SAMPLES for c in CANDIDATES if c[0] > 0 or name in ("features", "shadow")]


@pytest.mark.parametrize("name,candidates,bsdf,visibility", CANONICAL)
def test_canonical_matches_direct_path_tracing(name, candidates, bsdf, visibility, tmp_path):
    scene = scene_for(name, tmp_path)
    spp_di, spp_pt, bound = SAMPLES[name]
    di = render(scene, "restir-di", spp_di, seed=3, candidates=candidates,
                **{"candidates.bsdf": bsdf, "visibility": visibility, "spatial.rounds": 0, "temporal": False})
    pt = render(scene, "pt", spp_pt, seed=4)
    print(name, f"candidates={candidates}+{bsdf} visibility={visibility}")
    rep = check(di, pt.image, pt.batch_variance_of_mean, other=pt, tile=4)
    assert rep.mdb < bound


# name: (k, rounds, visibility, BSDF candidates); unshadowed reuse admits light candidates only
SPATIAL = {"k1-r1": (1, 1, "reuse", 1), "k3-r2": (3, 2, "reuse", 1), "k8-r1": (8, 1, "reuse", 1),
           "k4-r3": (4, 3, "reuse", 1), "k3-r2-unshadowed": (3, 2, "shading", 0),
           "k8-r1-unshadowed": (8, 1, "shading", 0)}


@pytest.mark.parametrize("config", list(SPATIAL))
@pytest.mark.parametrize("name", ["cornell-box", "features", "half-dark", "shadow"])
def test_spatial_reuse_matches_direct_path_tracing(name, config, tmp_path):
    k, rounds, visibility, bsdf = SPATIAL[config]
    scene = scene_for(name, tmp_path)
    spp_di, spp_pt, bound = SAMPLES.get(name, (8, 32, 0.03))
    di = render(scene, "restir-di", spp_di, seed=5, candidates=1 if name == "half-dark" else 4,
                **{"candidates.bsdf": bsdf, "visibility": visibility, "spatial.neighbors": k,
                   "spatial.rounds": rounds, "temporal": False})
    pt = render(scene, "pt", spp_pt, seed=6)
    print(name, config)
    rep = check(di, pt.image, pt.batch_variance_of_mean, other=pt, tile=4)
    assert rep.mdb < bound


@pytest.mark.parametrize("mutation", ["drop_empty_neighbors", "skip_zero_canonical"])
def test_mutations_are_detected(mutation):
    """Power check (docs/validation.md#power-checks-the-mutation-table): defects A3 and A1 must fail
    the same comparison.

    At 4x the samples of the unbiasedness test, the mutants' image-level |z| is about 10 (A3,
    brighter) and 9.5 (A1, darker) against a threshold of 3.8: detected with probability > 0.99.
    """
    scene = half_dark_scene()
    settings = {"candidates": 1, "spatial.neighbors": 4, "spatial.rounds": 1, "temporal": False,
                "debug.mutation": mutation}
    di = render(scene, "restir-di", 32, seed=5, **settings)
    pt = render(scene, "pt", 128, seed=6)
    with pytest.raises(AssertionError):
        check(di, pt.image, pt.batch_variance_of_mean, other=pt, tile=4)


def test_bsdf_candidates_with_unshadowed_reuse_are_refused():
    """BSDF candidates make W valid only for visibility-aware targets (docs/guide/restir_di.md)."""
    from restir.config import ConfigError

    with pytest.raises(ConfigError, match="visibility=reuse"):
        render(shadow_scene(), "restir-di", 1, seed=1, **{"candidates.bsdf": 1, "visibility": "shading"})


# the forced biased combination's power check in the slow tier (47 s); the fast tier keeps the
# default's half and the refusal (test_bsdf_candidates_with_unshadowed_reuse_are_refused)
@pytest.mark.parametrize("mutation,visibility", [("none", "reuse"), pytest.param("bsdf_unshadowed_reuse", "shading",
                                                                                 marks=pytest.mark.slow)])
def test_bsdf_candidates_need_visibility_aware_reuse(mutation, visibility):
    """Why the combination above is refused, and a power check: BSDF candidates' density omits V,
    so on light points occluded from a pixel its weights sum to N_L p_L / (N_L p_L + N_B p_B) < 1;
    a neighbour that sees such a point inherits the deficit unless targets include V. Under the
    blinds of the shadow scene the forced combination is about 0.4% dark, image |z| ~ 9 at
    these samples (threshold 4.4: t with 31 degrees of freedom); the visibility-aware default
    passes the same comparison."""
    settings = {"candidates": 1, "candidates.bsdf": 1, "visibility": visibility, "spatial.neighbors": 8,
                "spatial.rounds": 1, "temporal": False, "debug.mutation": mutation}
    di = render(shadow_scene(), "restir-di", 256, seed=5, **settings)
    pt = render(shadow_scene(), "pt", 1024, seed=6)
    if mutation == "none":
        check(di, pt.image, pt.batch_variance_of_mean, other=pt, tile=4)
    else:
        with pytest.raises(AssertionError):
            check(di, pt.image, pt.batch_variance_of_mean, other=pt, tile=4)


def independent_runs(scene, method, runs, frames, spp, size=24, seed0=100, **kw):
    """K independent runs of T frames (restir.validation.IndependentRuns)."""
    from restir.validation import IndependentRuns

    cfg = restir.RenderConfig(method=method, spp=spp, frames=frames, width=size, height=size, max_depth=2, **kw)
    return IndependentRuns(scene, cfg, runs, seed0)


TEMPORAL = {
    "cap1": dict(cap=1.0, rounds=0),
    "cap5": dict(cap=5.0, rounds=0),
    "cap20": dict(cap=20.0, rounds=0),
    "nocap": dict(cap=0.0, rounds=0),
    "temporal+spatial": dict(cap=20.0, rounds=2),
    "temporal+spatial-unshadowed": dict(cap=20.0, rounds=2, visibility="shading"),
}


@pytest.mark.parametrize("config", list(TEMPORAL))
@pytest.mark.parametrize("name", ["features", "half-dark", "shadow"])
def test_temporal_reuse_matches_direct_path_tracing(name, config, tmp_path):
    scene = scene_for(name, tmp_path)
    t = TEMPORAL[config]
    visibility = t.get("visibility", "reuse")
    settings = {"candidates": 1 if name == "half-dark" else 4, "temporal": True, "temporal.cap": t["cap"],
                "spatial.rounds": t["rounds"], "visibility": visibility,
                "candidates.bsdf": 1 if visibility == "reuse" else 0}
    # with spatial reuse in the default radius (5 px) the image mean varies more from run to run
    # than with a 30 px disk (which averaged over the whole 24x24 image): more runs
    runs = 32 if t["rounds"] else 24
    di = independent_runs(scene, "restir-di", runs=runs, frames=8, spp=1, settings=settings)
    pt = independent_runs(scene, "pt", runs=runs, frames=8, spp=4, seed0=500)
    print(name, config)
    rep = check(di, pt.image, pt.batch_variance_of_mean, other=pt, tile=4)
    assert rep.mdb < 0.05


@pytest.mark.parametrize("motion,speed", [("orbit", 3.0), ("dolly", 0.02)])
def test_reuse_with_a_moving_camera(motion, speed, tmp_path):
    """Temporal and spatial reuse while the camera moves: the reference path tracer renders the
    same per-frame cameras."""
    scene = scene_for("features", tmp_path)
    kw = dict(camera_motion=motion, camera_speed=speed)
    di = independent_runs(scene, "restir-di", runs=24, frames=8, spp=1, settings={"candidates": 4}, **kw)
    pt = independent_runs(scene, "pt", runs=24, frames=8, spp=4, seed0=500, **kw)
    print(motion)
    rep = check(di, pt.image, pt.batch_variance_of_mean, other=pt, tile=4)
    assert rep.mdb < 0.05


def test_uncapped_history_with_spatial_reuse_stays_finite():
    """temporal.cap = 0 ("no cap") with spatial reuse. Spatial reuse sums its inputs' confidences,
    so a history without any cap grew M by about (1 + V)^rounds per frame, and weights turned
    non-finite after 32-48 frames. "No cap" now caps the history at NO_CAP_RATIO x the current M."""
    from restir.api import _init_warp, make_integrator
    from restir.resampling.ris import NO_CAP_RATIO

    _init_warp()
    scene = restir.load_scene("builtin:cornell-box", width=32, height=32)
    cfg = restir.RenderConfig(method="restir-di", spp=1, settings={"candidates": 2, "temporal.cap": 0.0,
                                                                   "spatial.radius": 3.0, "spatial.rounds": 2})
    integ = make_integrator(scene, cfg)
    for f in range(64):
        integ.render_frame(f)
    M = integ.reservoirs.previous.numpy()["M"]
    assert integ.counters["nonfinite_weights"] == 0 and integ.counters["nonfinite_outputs"] == 0, integ.counters
    assert M.max() <= (NO_CAP_RATIO + 1) * (1 + 3) ** 2 * 1.0001  # the capped history plus one frame of reuse (k = 3)
    assert M.max() > 1e5  # and the history is long: the cap did not quietly shorten it


def test_confidence_stays_bounded_where_the_material_has_no_smooth_lobe():
    """Half the floor a mirror: its pixels' initial reservoirs have M = 0 (delta lobes only), so a
    history cap of cap x M_current was 0, which the cap read as "no cap"; spatial reuse summed the
    diffuse half's confidences into them every frame, and M grew without bound (2.3e20 by frame 39
    here; veach-bidir at 32x32 with the defaults: 1.5e34 by frame 79). Capped, M stays within one
    frame's growth: (1 + cap) x (1 + k)^rounds."""
    import copy

    from restir.api import _init_warp, make_integrator
    from restir.scene.builtin import builtin_scene

    _init_warp()
    tree = builtin_scene("cornell-box", width=24, height=24)
    mirror = copy.deepcopy(tree["floor"])        # the floor's second triangle, as a mirror
    mirror["faces"] = mirror["faces"][1:]
    mirror["bsdf"] = {"type": "conductor"}
    tree["floor"]["faces"] = tree["floor"]["faces"][:1]
    tree["floor_mirror"] = mirror
    scene = restir.load_scene(tree)
    integ = make_integrator(scene, restir.RenderConfig(method="restir-di", spp=1, settings={"candidates": 2}))
    for f in range(40):
        integ.render_frame(f)
    M = integ.reservoirs.previous.numpy()["M"]
    s = integ.settings
    assert M.max() <= (1 + s.temporal_cap) * (1 + s.spatial.neighbors) ** s.spatial.rounds, M.max()
    assert integ.counters["nonfinite_weights"] == 0


def k_trend(mutation="none"):
    """Image means (green channel) for k in {0, 1, 2, 4, 8, 16}; returns (max pairwise |z|,
    its Bonferroni threshold over 15 pairs at alpha 1e-3, |slope / SE| of the weighted trend)."""
    from scipy import stats as sps

    scene = half_dark_scene()
    ks = [0, 1, 2, 4, 8, 16]
    means, ses = [], []
    for k in ks:
        settings = {"candidates": 1, "temporal": False, "spatial.rounds": 1 if k else 0,
                    "spatial.neighbors": max(k, 1), "debug.mutation": mutation}
        r = render(scene, "restir-di", 8, seed=40 + k, **settings)
        frame_means = r.batches[..., 1].astype(np.float64).mean(axis=(1, 2))  # reuse correlates pixels,
        means.append(frame_means.mean())                                       # frames are independent
        ses.append(frame_means.std(ddof=1) / np.sqrt(len(frame_means)))
    means, ses = np.array(means), np.array(ses)
    z = max(abs(means[i] - means[j]) / np.hypot(ses[i], ses[j]) for i in range(6) for j in range(i + 1, 6))
    w = 1 / ses ** 2
    x = np.array(ks, float)
    xm = np.sum(w * x) / w.sum()
    slope = np.sum(w * (x - xm) * means) / np.sum(w * (x - xm) ** 2)
    trend = abs(slope) * np.sqrt(np.sum(w * (x - xm) ** 2))
    print("means", means, "max pair z", z, "slope/SE", trend)
    return z, sps.norm.isf(1e-3 / (2 * 15)), trend


def test_invariance_in_k():
    """I1 (docs/validation.md#level-4-invariance-tests): the image mean must not depend on the
    neighbour count, on the
    half-dark scene where a k-dependent bias (defects A2/A3) would show."""
    z, crit, trend = k_trend()
    assert z < crit and trend < 3.5


def test_invariance_in_k_catches_dropped_neighbors():
    """Power check: the A3 mutant brightens more as k grows."""
    z, crit, trend = k_trend("drop_empty_neighbors")
    assert z > crit or trend > 3.5


# (DI spp, PT spp) per frame: in veach-mis the four small, very bright spheres seen directly make
# the image-level variance of both sides ~6x larger per sample (antialiasing, not lighting).
SHARED = {"cornell-box": (8, 64), "veach-mis": (48, 256), "veach-bidir": (8, 64)}


@pytest.mark.slow
@pytest.mark.parametrize("name", list(SHARED))
def test_default_restir_di_on_shared_scenes(name):
    """Default ReSTIR DI (32 light + 1 BSDF candidates, visibility-aware reuse, temporal cap 2,
    3 neighbours x 1 round in the default radius, 5 px) against direct
    path tracing on the shared scenes, 32 independent runs x 8 frames at 32x32."""
    from tests.shared_scenes import scene_path

    scene = restir.load_scene(str(scene_path(name)))
    spp_di, spp_pt = SHARED[name]
    di = independent_runs(scene, "restir-di", runs=32, frames=8, spp=spp_di, size=32)
    pt = independent_runs(scene, "pt", runs=32, frames=8, spp=spp_pt, size=32, seed0=500)
    print(name)
    rep = check(di, pt.image, pt.batch_variance_of_mean, other=pt, tile=8)
    assert rep.mdb < 0.06


def test_every_frame_is_unbiased(tmp_path):
    """L1 (docs/validation.md#level-5-long-run-stability): frame t alone (not an average) is
    unbiased, for t in
    {0, 1, 2, 4, 8, 15}: 48 independent runs, Bonferroni over the 6 frames (alpha 1e-3 in all).
    Frame 0 also checks initialisation (no stale history); later frames catch drift."""
    from restir.validation import IndependentRuns
    from restir.validation.stats import RGBZTest

    scene = scene_for("features", tmp_path)
    runs, frames_t = 48, [0, 1, 2, 4, 8, 15]
    imgs = []
    for k in range(runs):
        cfg = restir.RenderConfig(method="restir-di", spp=1, frames=16, width=16, height=16, seed=2000 + k,
                                  max_depth=2, keep_frames=True, settings={"candidates": 4})
        imgs.append(restir.render(scene, cfg).frame_images)
    imgs = np.stack(imgs).astype(np.float64)  # (runs, frames, H, W, 3)
    ref = IndependentRuns(scene, restir.RenderConfig(method="pt", spp=16, frames=4, width=16, height=16, max_depth=2),
                          24, seed0=9000)
    from scipy import stats as sps

    for t in frames_t:
        x = imgs[:, t]
        skew = np.maximum(np.abs(np.nan_to_num(sps.skew(x, axis=0))), np.abs(ref.batch_skewness))
        kurt = np.maximum(np.nan_to_num(sps.kurtosis(x, axis=0)), ref.batch_excess_kurtosis)
        rep = RGBZTest(x.mean(0), x.var(0, ddof=1) / runs, ref.image, ref.batch_variance_of_mean, tile=4,
                       alpha=1e-3 / len(frames_t), df=runs - 1, batches=x, ref_batches=ref.batches,
                       skew=skew, kurtosis=kurt)
        print("frame", t, f"MDB {100 * rep.mdb:.2f}%")
        assert rep.passed, f"frame {t}:\n{rep}"


def test_no_drift_over_many_frames():
    """L2 (docs/validation.md#level-5-long-run-stability), fast version: 8 seeds x 600 frames, 8
    neighbours, batches of 50
    frames. A runaway temporal feedback loop (symptom b of the seed report) shows as a trend in
    the batch means or as growing maxima."""
    check_no_trend(*long_run_trend(seeds=8, frames=600, batch=50))


@pytest.mark.slow
def test_no_drift_over_many_frames_slow():
    """L2 at full length (docs/validation.md#level-5-long-run-stability): 16 seeds x 5000 frames,
    batches of 100."""
    check_no_trend(*long_run_trend(seeds=16, frames=5000, batch=100))


def test_drift_test_catches_a_feedback_loop():
    """Power check: over-weighting the history by 1.5 per frame feeds back through temporal and
    spatial reuse (docs/validation.md#level-5-long-run-stability); L2 must flag it."""
    with pytest.raises(AssertionError), np.errstate(all="ignore"):  # the mutant overflows to inf
        check_no_trend(*long_run_trend(seeds=8, frames=600, batch=50, mutation="temporal_overweight"))


@pytest.mark.parametrize("settings,motion", [({}, "none"), ({"visibility": "shading", "candidates.bsdf": 0, "spatial.rounds": 0}, "none"),
                                             ({"candidates.bsdf": 2}, "orbit")])
def test_fused_initial_and_temporal_is_the_split_pipeline_bit_for_bit(settings, motion):
    """The shipped pipeline runs initial RIS, visibility and temporal reuse as one kernel, and the
    spatial rounds write into the history's buffer; stages.split runs the three stages apart with
    a third reservoir buffer. The same functions in the same order: images and event counts must
    be identical bit for bit over frames (temporal reuse from the second sample on), with one
    reservoir buffer fewer. Also through ReSTIR PT's component (di.stages.split)."""
    scene = restir.load_scene("builtin:cornell-box-glossy", width=24, height=20)

    def run(method, key, split, extra):
        cfg = restir.RenderConfig(method=method, spp=2, frames=3, seed=4, settings={**extra, key: split},
                                  max_depth=None if method == "restir-di" else 4, camera_motion=motion)
        return restir.render(scene, cfg)

    for method, key, extra in (("restir-di", "stages.split", settings), ("restir-pt", "di.stages.split", {"direct": "restir-di"})):
        fused, split = run(method, key, False, extra), run(method, key, True, extra)
        assert np.array_equal(fused.image, split.image), method
        assert fused.stats["counters"] == split.stats["counters"]
        assert sum(fused.stats["rays_by_stage"].values()) == sum(split.stats["rays_by_stage"].values())
        prefix = "" if method == "restir-di" else "di."
        bpp_f, bpp_s = fused.stats["bytes_per_pixel"], split.stats["bytes_per_pixel"]
        assert f"{prefix}reservoirs_pass" not in bpp_f and bpp_s[f"{prefix}reservoirs_pass"] == 24
        assert bpp_s["total"] - bpp_f["total"] == 24
        if method == "restir-pt":
            break


def test_split_stages_refuse_fault_injections():
    scene = restir.load_scene("builtin:cornell-box", width=8, height=8)
    cfg = restir.RenderConfig(method="restir-di", settings={"stages.split": True, "debug.mutation": "temporal_overweight"})
    with pytest.raises(restir.ConfigError, match="stages.split"):
        restir.render(scene, cfg)
