"""Helpers shared by the test files (one module, so no test file imports another): the
statistical check every level uses, the emissive-cap sphere with its exact answer, the long-run
and invariance harnesses, and the path-reuse methods' stage-isolation matrix cell (ReSTIR PT
and Suffix ReSTIR run the same scenes). Scene builders live in tests/scenes.py; the shift tests'
device harnesses in tests/unit/shift_harness.py.
"""
import contextlib
import functools
import json
import os

import numpy as np

import restir
from restir.scene.builtin import sphere_cap_radiance
from restir.validation import IndependentRuns, assert_matches
from tests.scenes import bump_scene, feature_scene_named, mask_scene
from tests.shared_scenes import scene_path


# ------------------------------------------------------------------ the check
# Tessellated spheres and ray offsets (~1e-4 of the scene size) make the analytic answers
# exact only to about 1e-4; the furnace estimators are so nearly deterministic that the tests
# would detect that. Deviations below this margin count as zero in the analytic tests.
ANALYTIC_REL_TOL = 5e-4


def check(r, reference, reference_var=0.0, tile=8, rel_tol=0.0, other=None, abs_tol=0.0):
    """Test r against a reference value/image; `other` is the reference's result when it is noisy.
    In a matrix test not run through `run_cell` (ReSTIR DI's), the check's verdict is recorded
    when $RESTIR_RECORD_VERDICTS asks for it (the recorder under run_cell)."""
    kw = dict(other=other, tile=tile, rel_tol=rel_tol, abs_tol=abs_tol)
    if not _recording_check():
        return assert_matches(r, reference, reference_var, **kw)
    # the test may assert more after the check (an MDB bound): this verdict is the z-tests' alone
    with _recorded({"scope": "z-tests", "bound": None}) as entry:
        entry["inputs"] = (r, reference, reference_var, kw)
        rep = assert_matches(r, reference, reference_var, **kw)
        entry["mdb"] = rep.mdb
    return rep


def paired_difference(a, b):
    """Runs of two configurations with the same seeds, run by run: K estimates of
    E[a] - E[b] + mean(b), as an ImageBatches to test against mean(b) (a paired test). Run k of
    both shares its base paths, so the difference's variance is far below either's and a small
    bias of a against b (an option that should change nothing on average) is visible: on the
    glossy Cornell box at 16x16, 64 runs x 16 frames, an MDB of 0.2-1% where the unpaired test
    has 10%."""
    from restir.validation.runs import ImageBatches

    assert len(a.batches) == len(b.batches)
    return ImageBatches([x - y + b.image for x, y in zip(a.batches, b.batches)])


# ------------------------------------------------------------------ the emissive-cap sphere (exact answer)
SPHERE_CAP = dict(albedo=0.5, radiance=1.0, phi=0.05)
SPHERE_DEPTH = 4
SPHERE_EXACT = sphere_cap_radiance(SPHERE_CAP["albedo"], SPHERE_CAP["radiance"], SPHERE_CAP["phi"], SPHERE_DEPTH)


def sphere_cap(size=16):
    return restir.load_scene("builtin:sphere-cap", width=size, height=size, **SPHERE_CAP)


# ------------------------------------------------------------------ over frames and parameters
# (docs/validation.md#level-4-invariance-tests, docs/validation.md#level-5-long-run-stability)
def run_means(settings, runs=32, frames=8, method="restir-pt"):
    """Per-run image means (non-emitting pixels only: the cap is seen in a few) and the z-test."""
    cfg = restir.RenderConfig(method=method, spp=1, frames=frames, max_depth=SPHERE_DEPTH, settings=settings)
    r = IndependentRuns(sphere_cap(), cfg, runs, 300)
    rep = check(r, SPHERE_EXACT, rel_tol=ANALYTIC_REL_TOL)
    inside = np.abs(r.image.mean(-1) - SPHERE_EXACT) < 0.5 * SPHERE_EXACT
    return r.batches[:, inside].astype(np.float64).mean(axis=(1, 2)), rep.mdb


def check_flat(values, settings_of, method="restir-pt"):
    means, ses = [], []
    for v in values:
        m, mdb = run_means(settings_of(v), method=method)
        means.append(m.mean())
        ses.append(m.std(ddof=1) / np.sqrt(len(m)))
        print(v, f"mean {means[-1]:.6f} +- {ses[-1]:.6f} (exact {SPHERE_EXACT:.6f}), MDB {mdb:.4f}")
    x = np.log(np.asarray(values, float))
    w = 1 / np.asarray(ses) ** 2
    xm = np.sum(w * x) / w.sum()
    slope = np.sum(w * (x - xm) * np.asarray(means)) / np.sum(w * (x - xm) ** 2)
    t = slope * np.sqrt(np.sum(w * (x - xm) ** 2))
    print(f"slope/SE {t:.2f}")
    assert abs(t) < 3.5


def check_every_frame(method, runs=48, frames_t=(0, 1, 2, 4, 8, 15)):
    from restir.validation.stats import RGBZTest

    imgs = []
    for k in range(runs):
        cfg = restir.RenderConfig(method=method, spp=1, frames=max(frames_t) + 1, seed=2000 + k, max_depth=SPHERE_DEPTH,
                                  keep_frames=True)
        imgs.append(restir.render(sphere_cap(), cfg).frame_images)
    imgs = np.stack(imgs).astype(np.float64)
    ref = np.full(imgs.shape[2:], SPHERE_EXACT)
    from scipy import stats as sps

    for t in frames_t:
        x = imgs[:, t]
        rep = RGBZTest(x.mean(0), x.var(0, ddof=1) / runs, ref, 0.0, tile=4, alpha=1e-3 / len(frames_t),
                       df=runs - 1, batches=x, rel_tol=ANALYTIC_REL_TOL,
                       skew=np.abs(np.nan_to_num(sps.skew(x, axis=0))), kurtosis=np.nan_to_num(sps.kurtosis(x, axis=0)))
        print("frame", t, f"MDB {100 * rep.mdb:.2f}%")
        assert rep.passed, f"frame {t}:\n{rep}"


def long_run_trend(seeds, frames, batch, size=16, mutation="none", scene=None, method="restir-di", max_depth=2,
                   settings=None):
    """Per-batch image means (averaged over seeds) and per-batch maxima over a long run of
    default ReSTIR DI on the feature scene (temporal and spatial reuse feeding each other), or of
    another method, scene and settings."""
    if scene is None:
        from tests.scenes import feature_scene

        scene = feature_scene()
    if settings is None:
        settings = {"candidates": 4, "spatial.neighbors": 8}
    means, peaks = [], []
    for s in range(seeds):
        cfg = restir.RenderConfig(method=method, spp=1, frames=frames, width=size, height=size, seed=7000 + s,
                                  max_depth=max_depth, keep_frames=True,
                                  settings={**settings, "debug.mutation": mutation})
        f = restir.render(scene, cfg).frame_images.astype(np.float64).mean(-1)  # (frames, H, W)
        b = f[: frames - frames % batch].reshape(-1, batch, size, size)
        means.append(b.mean(axis=(1, 2, 3)))
        peaks.append(b.max(axis=(1, 2, 3)))
    return np.array(means), np.array(peaks)  # (seeds, batches)


def check_no_trend(means, peaks):
    from scipy import stats as sps

    assert np.all(np.isfinite(means)), "the image diverges to inf or NaN over frames (temporal feedback)"
    per_batch = means.mean(0)
    se = means.std(0, ddof=1) / np.sqrt(means.shape[0])
    x = np.arange(len(per_batch), dtype=float)
    w = 1 / se ** 2
    xm = np.sum(w * x) / w.sum()
    slope = np.sum(w * (x - xm) * per_batch) / np.sum(w * (x - xm) ** 2)
    t = slope * np.sqrt(np.sum(w * (x - xm) ** 2))
    rho, p = sps.spearmanr(x, peaks.max(0))
    print(f"batch means {np.round(per_batch, 4)}; slope/SE {t:.2f}; peak Spearman rho {rho:.2f} (p {p:.3f})")
    assert abs(t) < 3.5, "the image brightens or darkens over frames (temporal feedback)"
    assert not (rho > 0 and p < 1e-3), "the brightest pixels grow over frames (runaway spots)"


# ------------------------------------------------------------------ the path-reuse stage-isolation matrix
MATRIX_SIZE = 32
# A cell's camera: (RenderConfig.camera_motion, camera_speed, jitter); "centre" is the static
# camera with every primary ray through its pixel centre (RenderConfig.jitter False), reference too
MATRIX_CAMERAS = {"none": ("none", 1.0, True), "orbit": ("orbit", 3.0, True), "dolly": ("dolly", 0.02, True),
                  "centre": ("none", 1.0, False)}
# scene: (loader, max_depth, MDB bound, runs K, frames T)
MATRIX_SCENES = {
    "cornell-box-glossy": (lambda: restir.load_scene("builtin:cornell-box-glossy"), 5, 0.05, 64, 8),
    "veach-bidir": (lambda: restir.load_scene(str(scene_path("veach-bidir"))), 5, 0.06, 128, 32),
    "veach-mis": (lambda: restir.load_scene(str(scene_path("veach-mis"))), 3, 0.06, 384, 32),
    "indirect-room": (lambda: restir.load_scene("builtin:indirect-room"), 5, 0.06, 64, 16),
    "sphere-cap": (lambda: restir.load_scene("builtin:sphere-cap", albedo=0.5, radiance=1.0, phi=0.05), 5, 0.01, 64, 8),
    "bumps": (bump_scene, 5, 0.06, 64, 8),
    "masks": (mask_scene, 5, 0.06, 64, 8),
    # tests/data/feature_scene.py: delta lights mixed with an area light and an environment, delta
    # lights alone (points and spots; the sun), and a thin lens
    **{name: (functools.partial(feature_scene_named, name), 5, 0.06, 64, 8)
       for name in ("delta-lights", "delta-only", "sun", "thinlens")},
    # tests/data/feature_scene.py: the pbrt-v4 and glTF readers' materials (metallic-roughness, a
    # textured roughness, a per-point mixture)
    "materials": (functools.partial(feature_scene_named, "materials"), 5, 0.06, 64, 8),
    # tests/data/feature_scene.py: normal maps (five BSDFs, mirrored uvs) and a two-sided emitter
    "normalmaps-twosided": (functools.partial(feature_scene_named, "normalmaps-twosided"), 5, 0.06, 64, 8),
}
# Scenes that get some of each matrix's configurations, named in the matrix files (the bump maps:
# the cells whose shifts cross a tilted, wi-dependent shading frame; the lights and lens scenes:
# the cells of every stage and shift, with paths that end on delta lights or start on a lens); the
# rest get every one.
PARTIAL_MATRIX_SCENES = ("bumps", "masks")
LIGHT_MATRIX_SCENES = ("delta-lights", "delta-only", "sun", "thinlens")
# the materials and normal-map scenes get the light scenes' cells (every stage and shift, the defaults still and moving)
MATERIAL_MATRIX_SCENES = ("materials", "normalmaps-twosided")
FULL_MATRIX_SCENES = [n for n in MATRIX_SCENES
                      if n not in PARTIAL_MATRIX_SCENES + LIGHT_MATRIX_SCENES + MATERIAL_MATRIX_SCENES]
# The path tracer's spp per frame in the references: 16, and 48 on veach-mis, whose MDB the
# 16-spp reference set (5.8% on every configuration whatever the method's variance).
MATRIX_REFERENCE_SPP = {"veach-mis": 48}
# Configurations whose tails need more runs than their scene's K (measured MDB at the scene's K):
# direct=pt in the indirect room (7.3% at 64 x 16), the orbiting camera in veach-bidir (ReSTIR
# PT 8.8%, Suffix ReSTIR 7.8% at 128 x 32; with MCMC mutations 8.6%); ReSTIR PT's defaults on the masks, whose per-run
# means are heavy-tailed (light through the blinds is found by BSDF sampling only; excess kurtosis
# about 6): at 64 x 8 one tile read z = 5.45 (crit 4.93) while the image passed (z -0.5), and two
# replicates with fresh seeds passed (max tile |z| 2.04 and 2.31;
# docs/validation.md#results-restir-pt-stages-and-options).
MATRIX_RUNS = {("indirect-room", "C4-direct-pt"): 128,
               # direct=pt (ReSTIR PT's default since 2026-12-06) in the room: MDB 7.3% at 64 runs, 5.0% at 128
               **{("indirect-room", c): 128 for c in ("C4-defaults", "C4-orbit", "C4-dolly", "C4-centre")},
               ("masks", "C4-official"): 128, ("veach-bidir", "C4-orbit"): 384, ("veach-bidir", "C5-orbit"): 384,
               ("veach-bidir", "C6-mcmc-orbit"): 384, ("masks", "C4-defaults"): 128,
               # the defaults with independent neighbours, as the defaults' own cells
               ("indirect-room", "C4-independent"): 128, ("indirect-room", "C4-independent-orbit"): 128,
               ("veach-bidir", "C4-independent-orbit"): 384,
               # ReSTIR PT's defaults under delta lights: MDB 7.0% (mixed lights) and 5.9% (points and
               # spots alone) at 64 runs, the z-tests passing
               **{(n, c): 128 for n in ("delta-lights", "delta-only") for c in ("C4-defaults", "C4-orbit")}}


def matrix_runs(name, method, settings, motion, spp, seed0, runs=None):
    load, depth, _, scene_runs, frames = MATRIX_SCENES[name]
    motion, speed, jitter = MATRIX_CAMERAS[motion]
    cfg = restir.RenderConfig(method=method, spp=spp, frames=frames, width=MATRIX_SIZE, height=MATRIX_SIZE, max_depth=depth,
                              settings=settings, camera_motion=motion, camera_speed=speed, jitter=jitter)
    # RESTIR_TEST_WORKERS=n: the runs on n local processes, bitwise the same images (measured on
    # veach-mis, 48 runs: 0.38 s a run with 2 workers of one thread each, 0.47 s in one process
    # with 2 threads: at 32x32 a process is held back by its Python launch overhead)
    workers = int(os.environ.get("RESTIR_TEST_WORKERS", "1"))
    return IndependentRuns(load(), cfg, runs or scene_runs, seed0, workers=workers)


@functools.lru_cache(maxsize=None)
def matrix_reference(name, motion):
    return matrix_runs(name, "pt", {}, motion, MATRIX_REFERENCE_SPP.get(name, 16), 9000)


def dead_stages(stats: list) -> list:
    """The reuse passes whose shifts were tried and never succeeded over all of a cell's runs
    (each run's own `reuse_dead` summed: a pass that tries a few shifts a run, as Suffix ReSTIR's
    suffix spatial reuse in a room where most suffixes escape, can see none succeed in one run of
    64 by chance alone, 19 tries at a 14% success rate)."""
    tried, ok = {}, {}
    for st in stats:
        for stage, kinds in st["shifts"].items():
            tried[stage] = tried.get(stage, 0) + sum(k["tried"] for k in kinds.values())
            ok[stage] = ok.get(stage, 0) + sum(k["succeeded"] for k in kinds.values())
    return [stage for stage in tried if tried[stage] > 0 and ok[stage] == 0]


def run_cell(name, method, settings, motion, config=""):
    """One matrix cell: K runs of `method` on scene `name` against its reference (the sphere:
    the exact value); asserts a sound render (no fault injection, no dead reuse) and the MDB
    bound, and prints the cell's diagnostics."""
    _, depth, bound, runs, frames = MATRIX_SCENES[name]
    runs = MATRIX_RUNS.get((name, config), runs)
    with _recorded({"scope": "cell", "method": method, "scene": name, "config": config, "motion": motion,
                    "runs": runs, "frames": frames, "bound": bound}) as entry:
        r = matrix_runs(name, method, settings, motion, 1, 100, runs)
        assert all(s["settings"]["debug.mutation"] == "none" for s in r.stats)
        dead = dead_stages(r.stats)
        assert not dead, f"reuse dead in {dead}: {r.stats[0]['shifts']}"
        if name == "sphere-cap":
            args = (r, sphere_cap_radiance(0.5, 1.0, 0.05, depth), 0.0, dict(rel_tol=ANALYTIC_REL_TOL))
        else:
            ref = matrix_reference(name, motion)
            args = (r, ref.image, ref.batch_variance_of_mean, dict(other=ref, tile=8))
        entry["inputs"] = args
        rep = assert_matches(*args[:3], **args[3])
        entry["mdb"] = rep.mdb
        extra = r.stats[0].get("final_samples") or r.stats[0].get("gather_slots")
        print(name, f"K={runs} T={frames} MDB={rep.mdb:.4f}", r.stats[0]["shifts"], extra)
        assert rep.mdb < bound, f"MDB {rep.mdb:.4f} above the bound {bound}"


# ------------------------------------------------------------------ the matrix verdicts, recorded on request
# RESTIR_RECORD_VERDICTS=path.json: every matrix cell that runs adds its verdict to that JSON file
# ({"records": [...]}, one per test id, the latest run kept), which benchmarks/results_suite.py
# reads from benchmarks/results/verdicts.json. run_cell records the whole cell (scope "cell": its
# soundness asserts, z-tests and MDB bound); the matrix files that call `check` themselves
# (ReSTIR DI's) record that check (scope "z-tests"; the bound they assert after it is not seen).
# Recording never changes a test's outcome: an error while recording is printed and dropped.
RECORD_VERDICTS_ENV = "RESTIR_RECORD_VERDICTS"


def _current_test() -> str:
    return os.environ.get("PYTEST_CURRENT_TEST", "").split(" ")[0]


def _recording_check() -> bool:
    """A `check` to record: asked for, in a matrix test file (run_cell calls assert_matches)."""
    test = _current_test().split("::")[0]
    return bool(os.environ.get(RECORD_VERDICTS_ENV)) and os.path.basename(test).startswith("test_") \
        and test.endswith("_matrix.py")


@functools.lru_cache(maxsize=None)
def _commit() -> dict:
    import subprocess

    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

    def git(*args):
        return subprocess.run(["git", *args], cwd=root, capture_output=True, text=True, timeout=30).stdout.strip()

    return {"commit": git("rev-parse", "HEAD"), "dirty": bool(git("status", "--porcelain", "--untracked-files=no"))}


@contextlib.contextmanager
def _recorded(entry: dict):
    """Run a cell's body, then record its verdict: pass, fail (an AssertionError: the z-tests or
    an assertion of the cell) or error (any other exception); the exception goes on unchanged."""
    recording = bool(os.environ.get(RECORD_VERDICTS_ENV))
    try:
        yield entry
    except AssertionError as e:
        if recording:
            _write_verdict(entry, "fail", e)
        raise
    except Exception as e:
        if recording:
            _write_verdict(entry, "error", e)
        raise
    else:
        if recording:
            _write_verdict(entry, "pass", None)


def _write_verdict(entry: dict, verdict: str, error) -> None:
    try:
        import datetime
        import fcntl

        inputs = entry.pop("inputs", None)
        if entry.get("mdb") is None and inputs is not None:  # the z-tests failed: their MDB all the same
            from restir.validation.check import compare

            r, reference, var, kw = inputs
            entry["mdb"] = compare(r, reference, var, **kw).mdb
        test = _current_test()
        record = {"test": test, "file": test.split("::")[0], **entry, "verdict": verdict,
                  "message": str(error).strip().splitlines()[0][:300] if error is not None and str(error).strip()
                  else None, **_commit(),
                  "time": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")}
        record["mdb"] = None if record.get("mdb") is None else float(record["mdb"])
        path = os.environ[RECORD_VERDICTS_ENV]
        os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
        with open(path + ".lock", "w") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)
            data = {"records": []}
            if os.path.exists(path):
                with open(path) as f:
                    data = json.load(f)
            data["records"] = [x for x in data.get("records", []) if x.get("test") != test] + [record]
            tmp = f"{path}.{os.getpid()}.tmp"
            with open(tmp, "w") as f:
                json.dump(data, f, indent=1)
            os.replace(tmp, path)
    except Exception as e:  # noqa: BLE001  (recording never changes the test's outcome)
        print(f"{RECORD_VERDICTS_ENV}: the verdict was not recorded: {type(e).__name__}: {e}")
