"""Command-line smoke tests and user-error handling (one-line errors with file:line, exit 2)."""
import json
import subprocess
import sys

import numpy as np
import pytest

from restir.cli import main
from restir.image_io import read_exr
from tests.shared_scenes import requires_scenes, scene_path



def test_render_builtin_writes_exr_png_and_stats(tmp_path, capsys):
    out, png, stats = tmp_path / "a.exr", tmp_path / "a.png", tmp_path / "a.json"
    rc = main(["render", "builtin:cornell-box", "--width", "16", "--height", "12", "--spp", "2", "--frames", "2",
               "-o", str(out), "--png", str(png), "--stats", str(stats), "--set", "strategy=nee"])
    assert rc == 0
    img = read_exr(str(out))
    assert img.shape == (12, 16, 3) and np.isfinite(img).all() and img.mean() > 0
    assert png.stat().st_size > 0
    st = json.loads(stats.read_text())
    for key in ("stages", "total_ms", "rays_per_second", "bytes_per_pixel", "ms_per_frame"):
        assert key in st
    assert st["stages"]["path_trace"]["calls"] == 2 and st["bytes_per_pixel"]["total"] > 0
    assert st["settings"]["strategy"] == "nee" and st["frames"] == 2
    err = capsys.readouterr().err
    assert "path_trace" in err and "wrote" in err


def test_entry_point_runs_as_module(tmp_path):
    r = subprocess.run([sys.executable, "-m", "restir", "render", "builtin:furnace", "--spp", "1", "--quiet",
                        "-o", str(tmp_path / "f.exr")], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr


def write(tmp_path, text, name="scene.xml"):
    p = tmp_path / name
    p.write_text(text)
    return p


MINIMAL = """<scene version="3.0.0">
    <sensor type="perspective"><float name="fov" value="40"/>
        <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film>
    </sensor>
    {body}
</scene>"""


@pytest.mark.parametrize("body,line,message", [
    ('<shape type="rectangle"><float name="x" value="1"></shape>', 5, "malformed XML"),
    ('<shape type="teapot"/>', 5, "unsupported shape plugin type 'teapot'"),
    ('<shape type="obj"><string name="filename" value="missing.obj"/></shape>', 5, "mesh file 'missing.obj' not found"),
    ('<shape type="sphere"><float name="radius" value="nan"/></shape>', 5, "non-finite"),
    ('<shape type="rectangle"><bsdf type="diffuse"><rgb name="reflectance" value="0.5, inf, 0.5"/></bsdf></shape>', 5, "non-finite"),
    ('<shape type="rectangle"><ref id="nope"/></shape>', 5, "unknown id 'nope'"),
    ('<shape type="rectangle"><bsdf type="plastic_magic"/></shape>', 5, "unsupported bsdf plugin type"),
    ('<blob/>', 5, "unknown element <blob>"),
    ('<shape type="rectangle"><integer name="n" value="$undefined"/></shape>', 5, "undefined parameter"),
])
def test_bad_scene_is_one_line_error(tmp_path, capsys, body, line, message):
    p = write(tmp_path, MINIMAL.format(body=body))
    rc = main(["render", str(p), "-o", str(tmp_path / "x.exr"), "--quiet"])
    err = capsys.readouterr().err.strip()
    assert rc == 2
    assert len(err.splitlines()) == 1, err
    assert err.startswith(f"{p}:{line}: error:"), err
    assert message in err


def test_unreadable_texture_is_an_error(tmp_path, capsys):
    (tmp_path / "bad.png").write_bytes(b"not an image")
    body = '<shape type="rectangle"><bsdf type="diffuse"><texture type="bitmap" name="reflectance">' \
           '<string name="filename" value="bad.png"/></texture></bsdf></shape>'
    p = write(tmp_path, MINIMAL.format(body=body))
    assert main(["render", str(p), "--quiet", "-o", str(tmp_path / "x.exr")]) == 2
    err = capsys.readouterr().err.strip()
    assert "cannot read image 'bad.png'" in err and len(err.splitlines()) == 1


def test_missing_texture_stops_or_renders_grey(tmp_path, capsys):
    body = '<shape type="rectangle"><bsdf type="diffuse"><texture type="bitmap" name="reflectance">' \
           '<string name="filename" value="rug.png"/></texture></bsdf></shape>'
    p = write(tmp_path, MINIMAL.format(body=body))
    assert main(["render", str(p), "--quiet", "-o", str(tmp_path / "x.exr")]) == 2
    err = capsys.readouterr().err.strip()
    assert f"{p}:5" in err and "texture file 'rug.png' not found" in err and "--missing-textures grey" in err, err
    assert not (tmp_path / "x.exr").exists()
    assert main(["render", str(p), "-o", str(tmp_path / "x.exr"), "--missing-textures", "grey", "--spp", "1"]) == 0
    out = capsys.readouterr()
    assert "rug.png' not found: rendered as constant grey 0.5" in out.out + out.err
    assert (tmp_path / "x.exr").exists()


def test_unknown_parameter_is_a_warning_with_location(tmp_path, capsys):
    p = write(tmp_path, MINIMAL.format(body='<shape type="rectangle"><float name="radiuss" value="1"/></shape>'))
    rc = main(["render", str(p), "-o", str(tmp_path / "x.exr"), "--quiet"])
    assert rc == 0
    # --quiet silences the notes and tables, not the warnings
    err = capsys.readouterr().err
    assert err.startswith(f"warning: {p}:5: ") and "radiuss" in err and len(err.splitlines()) == 1, err
    # and the Python API gives them as SceneWarning
    import warnings

    import restir
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        restir.load_scene(str(p))
    msgs = [str(x.message) for x in w if issubclass(x.category, restir.SceneWarning)]
    assert any(f"{p}:5" in m and "radiuss" in m for m in msgs), msgs


def test_missing_scene_file_and_bad_settings(tmp_path, capsys):
    assert main(["render", str(tmp_path / "none.xml"), "--quiet"]) == 2
    assert "cannot read scene file" in capsys.readouterr().err
    assert main(["render", "builtin:furnace", "--set", "bogus=1", "--quiet", "-o", str(tmp_path / "x.exr")]) == 2
    assert "unknown setting 'bogus'" in capsys.readouterr().err
    assert main(["render", "builtin:nothing", "--quiet"]) == 2
    assert main(["render", "builtin:furnace", "--spp", "0", "--quiet"]) == 2
    import warp as wp

    if wp.get_cuda_device_count() == 0:
        assert main(["render", "builtin:furnace", "--device", "cuda", "--quiet"]) == 2
        assert "no CUDA device" in capsys.readouterr().err


def test_defines_override_defaults(tmp_path):
    import restir

    text = MINIMAL.replace('value="8"/><integer name="height"', 'value="$res"/><integer name="height"')
    text = text.replace("<scene version=\"3.0.0\">", '<scene version="3.0.0"><default name="res" value="8"/>')
    p = write(tmp_path, text.format(body='<shape type="rectangle"/>'))
    assert restir.load_scene(str(p)).camera.width == 8
    assert restir.load_scene(str(p), {"res": "12"}).camera.width == 12


@requires_scenes
@pytest.mark.parametrize("name", ["cornell-box", "veach-mis", "veach-bidir"])
def test_shared_scenes_load_and_render(tmp_path, name):
    rc = main(["render", str(scene_path(name)), "--width", "24", "--height", "16", "--spp", "1",
               "--quiet", "-o", str(tmp_path / "s.exr")])
    assert rc == 0
    img = read_exr(str(tmp_path / "s.exr"))
    assert np.isfinite(img).all() and img.mean() > 0


def test_validate_command(tmp_path, capsys):
    zmap = tmp_path / "z.png"
    rc = main(["validate", "builtin:cornell-box", "--runs", "6", "--frames", "2", "--width", "8", "--height", "8",
               "--set", "candidates=4", "--zmap", str(zmap)])
    out = capsys.readouterr().out
    assert rc in (0, 3), out  # pass (or inconclusive at this tiny size), never fail
    assert "verdict:" in out and "minimum detectable bias" in out and zmap.stat().st_size > 0
    assert main(["validate", "builtin:cornell-box", "--runs", "1"]) == 2  # a user error, not a traceback


# ------------------------------------------------------------------------- a new user's first hour
SMALL = ["--width", "8", "--height", "8", "--spp", "1", "--quiet"]


def one_line_error(capsys) -> str:
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    assert "error:" in err and "Traceback" not in err, err
    return err


@pytest.fixture
def no_work(monkeypatch):
    """Rendering or validating fails the test: output paths must be refused before the work."""
    import restir.api
    import restir.validation

    def refuse(*args, **kwargs):
        raise AssertionError("the render ran before the output paths were checked")

    monkeypatch.setattr(restir.api, "render", refuse)
    monkeypatch.setattr(restir.validation, "validate", refuse)


@pytest.mark.parametrize("args,message", [
    (["-o", "/proc/nope/x.exr"], "cannot create folder"),
    (["-o", "{file}/x.exr"], "is not a folder"),
    (["-o", "{tmp}/x.tif"], "unsupported extension '.tif'"),
    (["-o", "{tmp}/x"], "no extension"),
    (["-o", "{tmp}/"], "is a folder"),
    (["-o", "{tmp}/a.exr", "--stats", "{tmp}"], "is a folder"),
    (["-o", "{tmp}/a.exr", "--stats", "{tmp}/new/"], "is a folder"),
    (["-o", "{tmp}/a.exr", "--png", "{tmp}/a.exr"], "unsupported extension '.exr'"),
    (["-o", "{tmp}/a.exr", "--write-frames", "{file}"], "not a folder"),
])
def test_bad_output_path_fails_before_rendering(tmp_path, capsys, no_work, args, message):
    (tmp_path / "file.txt").write_text("a file, not a folder")
    args = [a.format(tmp=tmp_path, file=tmp_path / "file.txt") for a in args]
    assert main(["render", "builtin:cornell-box", *SMALL, *args]) == 2
    assert message in one_line_error(capsys)


def test_bad_zmap_path_fails_before_validating(tmp_path, capsys, no_work):
    assert main(["validate", "builtin:cornell-box", "--runs", "2", "--zmap", str(tmp_path / "z.tif")]) == 2
    assert "unsupported extension '.tif'" in one_line_error(capsys)


def test_output_format_follows_the_extension(tmp_path):
    from PIL import Image

    from restir.image_io import write_png

    base = ["render", "builtin:cornell-box", *SMALL, "--seed", "3", "--exposure", "1"]
    for ext in ("exr", "png", "npy"):
        assert main(base + ["-o", str(tmp_path / f"a.{ext}")]) == 0
    exr = read_exr(str(tmp_path / "a.exr"))
    npy = np.load(tmp_path / "a.npy")
    assert npy.dtype == np.float32 and npy.shape == (8, 8, 3)
    np.testing.assert_array_equal(npy, exr)  # the same linear image
    with Image.open(tmp_path / "a.png") as im:
        assert im.format == "PNG" and im.mode == "RGB"
        png = np.asarray(im)
    write_png(str(tmp_path / "b.png"), exr, 1.0)  # tonemapped as --png does, with --exposure
    np.testing.assert_array_equal(png, np.asarray(Image.open(tmp_path / "b.png")))


def test_validate_needs_a_small_enough_mdb_to_pass(capsys):
    import math
    import re

    args = ["validate", "builtin:cornell-box", "--runs", "3", "--frames", "2", "--width", "8", "--height", "8",
            "--set", "candidates=4"]
    assert main(args) == 3  # MDB in the thousands of percent: nothing could have been detected
    out = capsys.readouterr().out
    assert "verdict: inconclusive" in out, out
    mdb = float(re.search(r"minimum detectable bias[^:]*: ([0-9.]+)%", out).group(1)) / 100
    need = int(re.search(r"about ([0-9]+) runs", out).group(1))
    assert abs(need - math.ceil(3 * (mdb / 0.05) ** 2)) <= 0.01 * need + 1, out
    assert main(args + ["--max-mdb", "100000%"]) == 0  # a bound it meets: the z-tests decide
    assert "verdict: pass" in capsys.readouterr().out
    assert main(args + ["--max-mdb", "0.05"]) == 3  # the default, as a fraction
    assert "above the bound 5%" in capsys.readouterr().out
    for bad in ("5", "abc", "0", "-3%"):
        assert main(["validate", "builtin:cornell-box", "--max-mdb", bad]) == 2, bad
        assert "--max-mdb" in one_line_error(capsys)


def test_method_that_changes_max_depth_says_so(tmp_path, capsys):
    stats = tmp_path / "s.json"
    args = ["render", "builtin:cornell-box", "--method", "restir-di", "--width", "8", "--height", "8", "--spp", "1",
            "--set", "candidates=2", "-o", str(tmp_path / "a.exr"), "--stats", str(stats)]
    assert main(args) == 0
    err = capsys.readouterr().err
    notes = json.loads(stats.read_text())["notes"]
    assert len(notes) == 1 and "max_depth 2" in notes[0] and "max_depth -1" in notes[0], notes
    assert f"note: {notes[0]}" in err, err
    assert main(args + ["--quiet"]) == 0
    assert "note" not in capsys.readouterr().err
    assert main(args + ["--max-depth", "2"]) == 0  # asked for: nothing changed behind the user's back
    assert json.loads(stats.read_text())["notes"] == []


def test_unused_define_is_a_warning_naming_the_file(tmp_path, capsys):
    import warnings

    import restir

    p = write(tmp_path, MINIMAL.format(body='<shape type="rectangle"/>'))
    assert main(["render", str(p), "-D", "spp=4", "--spp", "1", "-o", str(tmp_path / "x.exr")]) == 0
    err = capsys.readouterr().err
    assert f"warning: {p}: -D spp=4: the scene never uses 'spp'" in err, err
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        restir.load_scene(str(p), {"spp": "4"})
        restir.load_scene(str(p))
    msgs = [str(x.message) for x in w if issubclass(x.category, restir.SceneWarning) and "-D" in str(x.message)]
    assert len(msgs) == 1 and str(p) in msgs[0], msgs


def test_used_define_gives_no_warning(tmp_path):
    import warnings

    import restir

    text = MINIMAL.replace('value="8"/><integer name="height"', 'value="$res"/><integer name="height"')
    text = text.replace("<scene version=\"3.0.0\">", '<scene version="3.0.0"><default name="res" value="8"/>')
    p = write(tmp_path, text.format(body='<shape type="rectangle"/>'))
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        assert restir.load_scene(str(p), {"res": "4"}).camera.width == 4
    assert not [x for x in w if "-D" in str(x.message)]


@pytest.mark.parametrize("args", [["-D", "spp"], ["--set", "candidates"], ["--frames", "x"], ["--bogus"]])
def test_argument_errors_are_one_line(capsys, args):
    assert main(["render", "builtin:cornell-box", *args]) == 2
    err = one_line_error(capsys)
    assert err.startswith("restir") and ": error: " in err and "--help" in err


def test_setting_type_errors_read_well():
    from restir.config import ConfigError, parse_value

    with pytest.raises(ConfigError, match="'abc' is not an int$"):
        parse_value("abc", 3)
    with pytest.raises(ConfigError, match="'abc' is not a float$"):
        parse_value("abc", 0.5)


def run_module(args, env=None, cwd=None):
    import os

    return subprocess.run([sys.executable, "-m", "restir", *args], capture_output=True, text=True, cwd=cwd,
                          env={**os.environ, **(env or {})})


def test_quiet_cpu_render_prints_nothing(tmp_path):
    r = run_module(["render", "builtin:cornell-box", *SMALL, "-o", str(tmp_path / "a.exr")])
    assert r.returncode == 0 and "CUDA driver" not in r.stderr and r.stderr.strip() == "", r.stderr


def test_driver_warning_filter_keeps_every_other_line(capfd):
    import os

    from restir.api import _CUDA_DRIVER_WARNING, _stderr_without

    with _stderr_without(_CUDA_DRIVER_WARNING):
        os.write(2, b"Warp CUDA warning: Could not find or load the NVIDIA CUDA driver. GPU execution will not be "
                    b"available.\nWarp CUDA error: something real\n")
    assert capfd.readouterr().err == "Warp CUDA error: something real\n"


def test_cuda_request_keeps_warps_driver_warning(tmp_path):
    import warp as wp

    wp.init()
    if wp.get_cuda_device_count() > 0:
        pytest.skip("a CUDA device is present")
    r = run_module(["render", "builtin:cornell-box", *SMALL, "--device", "cuda", "-o", str(tmp_path / "a.exr")])
    assert r.returncode == 2 and "no CUDA device" in r.stderr
    import ctypes

    try:
        ctypes.CDLL("libcuda.so.1")
    except OSError:  # no driver at all: Warp's reason is the message the user needs
        assert "CUDA driver" in r.stderr, r.stderr


def test_version(capsys):
    import restir

    assert main(["--version"]) == 0
    assert capsys.readouterr().out.strip() == f"restir {restir.__version__}"


def test_help_shows_defaults_and_builtins(capsys):
    assert main(["render", "--help"]) == 0
    out = " ".join(capsys.readouterr().out.split())
    for text in ("frames to render and average (default: 1)", "(default: cpu)", "(default: pt)",
                 "(default: <scene name>.exr in the current folder)", "furnace", "max_depth 64"):
        assert text in out, (text, out)
    assert "(default: None)" not in out
    assert main(["validate", "--help"]) == 0
    out = " ".join(capsys.readouterr().out.split())
    assert "(default: 32)" in out and "--max-mdb" in out and "(default: 5%)" in out, out


def test_warp_verbose_zero_means_off():
    import os

    code = "import restir, warp; print(warp.config.log_level == warp.LOG_ERROR)"
    for value, quiet in (("0", "True"), ("false", "True"), ("1", "False")):
        r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                           env={**os.environ, "RESTIR_WARP_VERBOSE": value})
        assert r.stdout.strip() == quiet, (value, r.stdout, r.stderr)


def test_default_output_is_the_scene_name_in_the_current_folder(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["render", "builtin:cornell-box", *SMALL]) == 0
    assert (tmp_path / "cornell-box.exr").is_file() and not (tmp_path / "out").exists()
    p = write(tmp_path, MINIMAL.format(body='<shape type="rectangle"/>'), name="room.xml")
    assert main(["render", str(p), "--spp", "1", "--quiet"]) == 0
    assert read_exr(str(tmp_path / "room.exr")).shape == (8, 8, 3)


def test_write_frames(tmp_path):
    frames = tmp_path / "frames"
    assert main(["render", "builtin:cornell-box", *SMALL, "--frames", "3", "-o", str(tmp_path / "a.exr"),
                 "--write-frames", str(frames)]) == 0
    assert sorted(p.name for p in frames.iterdir()) == ["frame_0000.exr", "frame_0001.exr", "frame_0002.exr"]
    imgs = [read_exr(str(frames / f"frame_{i:04d}.exr")) for i in range(3)]
    assert not np.array_equal(imgs[0], imgs[1])  # separate frames, not three copies of the mean
    np.testing.assert_allclose(np.mean(imgs, axis=0), read_exr(str(tmp_path / "a.exr")), rtol=1e-5, atol=1e-7)


def test_info_lists_methods_settings_and_builtins(capsys):
    from restir.cli import main
    from restir.integrators import METHODS
    from restir.scene.builtin import BUILTINS

    assert main(["info"]) == 0
    out = capsys.readouterr().out
    for name, cls in METHODS.items():
        assert set(cls.SETTINGS_DOC) == set(cls.SETTINGS), f"{name}: every setting needs a one-line meaning"
        assert f"  {name}: " in out
        for key in cls.SETTINGS:
            assert f"    {key}=" in out and cls.SETTINGS_DOC[key] in out
    for name in BUILTINS:
        assert f"  {name} " in out
