"""Command-line smoke tests and user-error handling (one-line errors with file:line, exit 2)."""
import json
import subprocess
import sys

import numpy as np
import pytest

from restir.cli import main
from restir.image_io import read_exr

SHARED = __import__("pathlib").Path(__file__).resolve().parents[3] / "shared" / "scenes"


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


def test_unknown_parameter_is_a_warning_with_location(tmp_path, capsys):
    p = write(tmp_path, MINIMAL.format(body='<shape type="rectangle"><float name="radiuss" value="1"/></shape>'))
    rc = main(["render", str(p), "-o", str(tmp_path / "x.exr"), "--quiet"])
    assert rc == 0
    # --quiet silences the console, so check the warning through the Python API
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


@pytest.mark.skipif(not SHARED.exists(), reason="../shared/scenes not present")
@pytest.mark.parametrize("name", ["cornell-box", "veach-mis", "veach-bidir"])
def test_shared_scenes_load_and_render(tmp_path, name):
    rc = main(["render", str(SHARED / name / "scene.xml"), "--width", "24", "--height", "16", "--spp", "1",
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
