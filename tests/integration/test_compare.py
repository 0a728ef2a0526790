"""`restir compare`: budgets, metrics against an independent computation from the written EXRs,
the reference cache, input errors before any work, and the HTML report operated in a real browser
(Debian's chromium through Selenium; `make test` installs both)."""
import json
import math
import os
import subprocess
import sys

import numpy as np
import pytest

import restir
from restir.compare import MethodSpec, compare
from restir.compare.frames import _Blocks
from restir.compare.headline import at_spp
from restir.config import ConfigError
from restir.image_io import read_exr
from tests.browser import chromium

ARTIFACTS = os.path.join("out", "artifacts")


@pytest.fixture(scope="module")
def comparison(tmp_path_factory):
    """pt at 2 spp per frame and restir-di with 8 neighbours, 16 samples per pixel each, on the
    Cornell box at 32x32 against a 64-spp path-traced reference (cached in a temporary folder)."""
    cache = tmp_path_factory.mktemp("cache")
    os.environ["RESTIR_CACHE"] = str(cache)
    try:
        scene = restir.load_scene("builtin:cornell-box")
        result = compare(scene, ["pt:spp=2", "restir-di:spatial.neighbors=8"], reference_spp=64, equal_spp=16,
                         warmup=2, width=32, height=32, correlation_runs=4, denoise=True)
    finally:
        del os.environ["RESTIR_CACHE"]
    return result, cache


def test_equal_samples_budget(comparison):
    result, _ = comparison
    pt, di = result.methods
    assert (pt.spp, pt.frames) == (2, 8) and (di.spp, di.frames) == (1, 16)
    assert result.notes and "max_depth 2" in result.notes[0]  # restir-di computes depth 2: all compared there
    assert pt.stats["max_depth"] == di.stats["max_depth"] == 2
    assert pt.metrics["frames_after_warmup"] == 6 and di.metrics["frames_after_warmup"] == 14
    assert np.all(np.diff(pt.frame_seconds) > 0)
    for m in result.methods:  # both unbiased: within the image test's threshold (t, 7 and 15 df: about 6)
        assert abs(m.metrics["mean_z"]) < 5.0 and m.metrics["mean_mdb"] > 0, m.metrics


def test_metrics_match_the_written_images(comparison, tmp_path):
    """The report's numbers, recomputed from its EXRs with numpy and flip_evaluator directly."""
    import flip_evaluator

    from restir.compare.report import write_report

    result, _ = comparison
    write_report(result, str(tmp_path))
    data = json.load(open(tmp_path / "comparison.json"))
    ref = read_exr(str(tmp_path / "images" / "0.exr")).astype(np.float64)
    assert np.allclose(ref, result.reference.image, rtol=1e-6, atol=1e-7)
    listing = json.load(open(tmp_path / "images.json"))
    files = {(e["method"], e["kind"]): e["file"] for e in listing}
    assert files[("reference", "accumulated")] == "images/0.exr"
    for m, res in zip(data["methods"], result.methods):
        img = read_exr(str(tmp_path / files[(m["label"], "accumulated")])).astype(np.float64)
        last = read_exr(str(tmp_path / files[(m["label"], "frame")])).astype(np.float64)
        assert np.mean((last - ref) ** 2 / (ref ** 2 + 0.01)) == pytest.approx(m["frame_relmse"][-1], rel=1e-4)
        rel = np.mean((img - ref) ** 2 / (ref ** 2 + 0.01))
        ape = np.mean(np.abs(img - ref) / (np.abs(ref) + 0.01))
        fl = flip_evaluator.evaluate(np.clip(ref, 0, None).astype(np.float32), np.clip(img, 0, None).astype(np.float32),
                                     "HDR", applyMagma=False)[1]
        assert m["metrics"]["relmse_accumulated"] == pytest.approx(rel, rel=1e-5)
        assert m["metrics"]["mape"] == pytest.approx(ape, rel=1e-5)
        assert m["metrics"]["flip"] == pytest.approx(fl, rel=1e-4)
        assert m["metrics"]["mean_ratio"] == pytest.approx(img.mean() / ref.mean(), rel=2e-2)
        assert m["accumulated_relmse"][-1] == m["metrics"]["relmse_accumulated"]
        assert len(m["frame_relmse"]) == m["frames"] and len(m["frame_seconds"]) == m["frames"]


def test_reference_is_cached(comparison, monkeypatch):
    """A second comparison with the same scene and settings loads the reference from the cache
    (no path-tracer render), and a changed scene gets a new key."""
    import restir.api

    result, cache = comparison
    files = list((cache / "references").iterdir())
    assert len(files) == 1
    monkeypatch.setenv("RESTIR_CACHE", str(cache))
    calls = []
    real = restir.api.render
    monkeypatch.setattr(restir.api, "render", lambda *a, **k: calls.append(1) or real(*a, **k))
    scene = restir.load_scene("builtin:cornell-box")
    again = compare(scene, ["restir-di"], reference_spp=64, frames=2, width=32, height=32, correlation_runs=0)
    assert not calls and np.array_equal(again.reference.image, result.reference.image)
    scene.tri_emission = scene.tri_emission * 2.0
    compare(scene, ["restir-di"], reference_spp=64, frames=2, width=32, height=32, correlation_runs=0)
    assert calls and len(list((cache / "references").iterdir())) == 2


def test_equal_time_budget(tmp_path, monkeypatch):
    """Every method's frames until the budget is spent; the path tracer also at the whole spp on
    both sides of restir-di's frame time (its worth in spp from the fit of the comparison's own
    probes), interpolated between them as the baseline of the headline."""
    monkeypatch.setenv("RESTIR_CACHE", str(tmp_path))
    scene = restir.load_scene("builtin:cornell-box")
    r = compare(scene, ["pt", "restir-di"], reference_spp=16, equal_time=0.5, width=16, height=16,
                correlation_runs=0)
    for m in r.methods:  # frames until the budget is spent, the crossing frame kept
        assert m.seconds >= 0.5 and m.frame_seconds[-2] < 0.5 and m.frames >= 2
    assert r.methods[0].frames > r.methods[1].frames  # the path tracer's frames are cheaper
    fit = r.frame_time_fit
    assert fit and fit["per_spp_ms"] > 0 and fit["probes"][0]["spp"] == 1
    di = r.methods[1]
    spp = max(1.0, (di.metrics["ms_per_frame"] - fit["fixed_ms"]) / fit["per_spp_ms"])
    assert fit["spp_of"]["restir-di"] == pytest.approx(spp)
    matched = sorted((m for m in r.methods if m.method == "pt" and "restir-di" in m.frame_time_of),
                     key=lambda m: m.spp)
    assert [m.spp for m in matched] == sorted({math.floor(spp), math.ceil(spp)})
    assert (matched[0] is r.methods[0]) == (matched[0].spp == 1)  # the given pt at 1 spp is used as it is
    assert len(r.methods) == 2 + sum(m.spp != 1 for m in matched)
    (h,) = r.headline
    assert h["method"] == "restir-di" and h["basis"] == "equal frame time" and h["baseline_spp"] == pytest.approx(spp)
    assert h["baseline"] in [m.label for m in matched]
    expected = at_spp(matched[0], matched[-1], spp, "relmse_frame")
    assert h["raw_frame"] == pytest.approx(expected / di.metrics["relmse_frame"])
    lo, hi = (m.metrics["relmse_frame"] for m in (matched[0], matched[-1]))
    assert min(lo, hi) <= expected <= max(lo, hi)
    assert h["denoised_frame"] is None and "per-frame relMSE raw" in h["text"]
    assert any("each method's frame time" in n for n in r.notes)


def test_structure_and_denoised_columns(comparison):
    """The structure metrics and the denoised columns are in every method's metrics (their values
    are tested against exact cases in tests/unit/test_error_structure.py), the denoised subset is
    every frame after the warm-up here (at most 16), and the headline at equal samples is against
    the path tracer given."""
    result, _ = comparison
    for m in result.methods:
        x = m.metrics
        assert set(x["correlation_factor"]) == {"2", "4", "8", "16"}
        assert all(v is None or v > 0 for v in x["correlation_factor"].values())
        assert -1 <= x["temporal_correlation"] <= 1
        assert m.radial["runs"] == 4 and m.radial["frame"] == 2 and len(m.radial["values"]) == 16
        assert all(np.isfinite(m.radial["values"][:8]))
        assert m.denoise_subset == list(range(2, m.frames)) and x["denoised_frames"] == m.frames - 2
        assert x["relmse_denoised_frame"] > 0 and x["flip_denoised_frame"] > 0 and x["flip_frame"] > 0
        assert m.denoised.shape == (32, 32, 3)
    pt, di = result.methods
    # (at 32x32 the directly seen light's edge pixels dominate every correlation: values here are
    # about +-0.2 from frame to frame, so only their range is checked)
    (h,) = result.headline
    assert (h["method"], h["baseline"], h["basis"]) == (di.label, pt.label, "equal samples")
    assert h["denoised_frame"] == pytest.approx(pt.metrics["relmse_denoised_frame"] / di.metrics["relmse_denoised_frame"])


def test_blocks_stay_equal_and_bounded():
    b = _Blocks()
    for i in range(1000):
        b.add(np.full((2, 2, 3), float(i)))
    full = b.full()
    assert 32 <= len(full) <= 64 and len(b.sums) <= 64
    n = b.length
    assert np.allclose(full[:, 0, 0, 0], [np.mean(range(k * n, (k + 1) * n)) for k in range(len(full))])


def test_method_specs():
    s = MethodSpec.parse("restir-di:spatial.neighbors=8, spp=2")
    assert (s.method, s.settings, s.spp) == ("restir-di", {"spatial.neighbors": "8"}, 2)
    for bad, msg in (("nope", "unknown method"), ("restir-di:no.such=1", "unknown setting"),
                     ("restir-di:candidates", "not key=value"), ("pt:spp=0", "spp must be"),
                     ("restir-di:candidates=x", "candidates")):
        with pytest.raises(ConfigError, match=msg):
            MethodSpec.parse(bad)


def test_cli_refuses_bad_input_before_work(tmp_path):
    """Errors in one line, exit 2, nothing rendered (no reference in the cache afterwards)."""
    env = {**os.environ, "RESTIR_CACHE": str(tmp_path / "cache")}
    cases = [
        (["--method", "pt", "--method", "restir-di:bogus=1"], "unknown setting 'bogus'"),
        (["--method", "pt", "--json", str(tmp_path / "x.txt")], "--json"),
        (["--method", "pt", "--equal-time", "1", "--equal-spp", "4"], "not allowed with"),
        (["--method", "pt", "--reference", str(tmp_path / "missing.exr")], "no such file"),
        (["--method", "pt", "--correlation-runs", "2"], "at least 3"),
        (["--method", "pt", "--equal-time", "1", "--workers", "2", "--correlation-runs", "0"], "one after another"),
        ([], "at least one --method"),
    ]
    for extra, msg in cases:
        p = subprocess.run([sys.executable, "-m", "restir", "compare", "builtin:cornell-box", "--width", "8",
                            "--height", "8", *extra], capture_output=True, text=True, env=env, timeout=120)
        assert p.returncode == 2 and msg in p.stderr, (extra, p.stderr)
    assert not (tmp_path / "cache").exists()


def report_images(result):
    """The report's images in its order: the reference, then per method its accumulated image,
    its last frame and, when denoised, the last frame denoised."""
    images = [result.reference.image]
    for m in result.methods:
        images += [m.image, m.last_frame] + ([m.denoised] if m.denoised is not None else [])
    return images


def operate_report(index, images, screenshot, denoised=False):
    """Open the report at `index` in chromium and operate it: every image decoded to `images` (the
    reference first) and finite, every plot drawn (the radial correlation's too), a number key
    switches the method shown (and the canvas changes), 'f' its last frame, 'd' the denoised last
    frame and back (when `denoised`), the wheel zooms (the view and the canvas change), 'e' shows
    the error view, no console errors; a screenshot is kept in out/artifacts/."""
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.actions.wheel_input import ScrollOrigin
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support.ui import WebDriverWait

    driver = chromium()
    try:
        driver.get("file://" + os.path.abspath(index))
        WebDriverWait(driver, 60).until(lambda d: d.execute_script("return document.body.dataset.ready === '1'"))
        assert driver.execute_script("return IMAGES.length") == len(images)
        stats = driver.execute_script("return IMAGES.map(im => [im.rgb.length, im.rgb.every(Number.isFinite), "
                                      "im.rgb.reduce((a, b) => a + b, 0) / im.rgb.length])")
        for (length, finite, mean), img in zip(stats, images):
            assert length == img.size and finite and mean == pytest.approx(float(np.mean(img)), rel=2e-3)
        assert driver.execute_script("return document.querySelectorAll('.js-plotly-plot .main-svg').length") >= 6
        assert driver.execute_script("return document.getElementById('plot-radial') !== null")
        main = driver.find_element(By.ID, "main")
        pixels = lambda: driver.execute_script("return document.getElementById('main').toDataURL()")  # noqa: E731
        before = pixels()
        ActionChains(driver).send_keys("0").perform()
        assert driver.execute_script("return restirView.index") == 0
        assert driver.find_element(By.ID, "shown").text == "reference"
        assert pixels() != before
        ActionChains(driver).send_keys("2").perform()
        assert driver.execute_script("return restirView.method") == 2
        label = driver.execute_script("return D.methods[2].label")
        assert driver.find_element(By.ID, "shown").text == label
        accumulated = pixels()
        ActionChains(driver).send_keys("f").perform()
        assert driver.find_element(By.ID, "shown").text == label + ": last frame" and pixels() != accumulated
        if denoised:
            raw = pixels()
            ActionChains(driver).send_keys("d").perform()
            assert driver.execute_script("return restirView.kind") == "denoised"
            assert driver.find_element(By.ID, "shown").text == label + ": last frame denoised"
            assert pixels() != raw
            ActionChains(driver).send_keys("d").perform()  # d toggles back to the raw frame
            assert driver.execute_script("return restirView.kind") == "frame" and pixels() == raw
            ActionChains(driver).send_keys("d").perform()
        ActionChains(driver).send_keys("e").perform()  # the error view of the frame shown
        assert pixels() != accumulated
        ActionChains(driver).send_keys("e").perform()
        shown = pixels()
        ActionChains(driver).scroll_from_origin(ScrollOrigin.from_element(main), 0, -300).perform()
        WebDriverWait(driver, 5).until(lambda d: d.execute_script("return restirView.scale") > 1.0)
        assert pixels() != shown
        ActionChains(driver).send_keys("e").perform()
        assert driver.execute_script("return restirView.error") is True
        os.makedirs(ARTIFACTS, exist_ok=True)
        driver.save_screenshot(os.path.join(ARTIFACTS, screenshot))
        errors = [e for e in driver.get_log("browser") if e["level"] == "SEVERE"]
        assert not errors, errors
    finally:
        driver.quit()


def test_report_in_a_browser(comparison, tmp_path):
    from restir.compare.report import write_report

    result, _ = comparison
    index = write_report(result, str(tmp_path / "report"))
    operate_report(index, report_images(result), "compare_report.png", denoised=True)


@pytest.mark.slow
def test_the_documented_command_in_a_browser(tmp_path):
    """The documented command as written (20 s per method at the Cornell box's own 256x256), its report
    operated in chromium, its JSON's numbers recomputed from the report's EXRs."""
    out = tmp_path / "cmp"
    env = {**os.environ, "RESTIR_CACHE": str(tmp_path / "cache")}
    p = subprocess.run([sys.executable, "-m", "restir", "compare", "builtin:cornell-box", "--method", "pt",
                        "--method", "restir-di", "--equal-time", "20", "--report", str(out)],
                       capture_output=True, text=True, env=env, timeout=1800)
    assert p.returncode == 0, p.stderr
    data = json.load(open(out / "comparison.json"))
    listing = json.load(open(out / "images.json"))
    images = [read_exr(str(out / e["file"])) for e in listing]
    accumulated = {e["method"]: img for e, img in zip(listing, images) if e["kind"] == "accumulated"}
    for m in data["methods"]:
        img = accumulated[m["label"]]
        assert m["seconds"] >= 20 and m["frames"] >= 2
        ref = images[0].astype(np.float64)
        rel = np.mean((img - ref) ** 2 / (ref ** 2 + 0.01))
        assert m["metrics"]["relmse_accumulated"] == pytest.approx(rel, rel=1e-4)
    operate_report(str(out / "index.html"), images, "compare_report_documented.png")

@pytest.mark.slow
def test_mitsuba_reference(tmp_path, monkeypatch):
    """--reference mitsuba: Mitsuba 3 (scalar_rgb unless DRJIT_LIBLLVM_PATH is set) renders the same
    XML at the compared size and depth; our path tracer agrees with it (mean ratio z), and the
    reference is cached."""
    pytest.importorskip("mitsuba")  # the `reference` extra
    from tests.shared_scenes import scene_path

    monkeypatch.setenv("RESTIR_CACHE", str(tmp_path))
    path = str(scene_path("cornell-box"))
    scene = restir.load_scene(path)
    r = compare(scene, ["pt:spp=4"], reference="mitsuba", reference_spp=256, frames=16, width=32, height=32,
                max_depth=4, scene_file=path)
    assert r.reference.source.startswith("mitsuba") and r.reference.blocks.shape == (16, 32, 32, 3)
    m = r.methods[0].metrics
    assert abs(m["mean_z"]) < 5 and abs(m["mean_ratio"] - 1) < 0.05, m
    assert len(list((tmp_path / "references").iterdir())) == 1
    with pytest.raises(ConfigError, match="builtin scenes have none"):
        compare(restir.load_scene("builtin:cornell-box"), ["pt"], reference="mitsuba", frames=2, width=8, height=8,
                scene_file="builtin:cornell-box")
