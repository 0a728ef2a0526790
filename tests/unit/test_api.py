"""The Python API as a Mitsuba user would call it (no argument silently ignored)."""
import re
import pathlib

import numpy as np
import pytest

import restir
from restir.scene.builtin import builtin_scene

XML = """<scene version="3.0.0">
  <default name="spp" value="16"/>
  <default name="res" value="32"/>
  <default name="albedo" value="0.5"/>
  <integrator type="path"><integer name="max_depth" value="3"/></integrator>
  <sensor type="perspective">
    <float name="fov" value="40"/>
    <transform name="to_world"><lookat origin="0, 0, 4" target="0, 0, 0" up="0, 1, 0"/></transform>
    <sampler type="independent"><integer name="sample_count" value="$spp"/></sampler>
    <film type="hdrfilm"><integer name="width" value="$res"/><integer name="height" value="$res"/></film>
  </sensor>
  <shape type="rectangle">
    <bsdf type="diffuse"><rgb name="reflectance" value="$albedo"/></bsdf>
  </shape>
  <emitter type="constant"><rgb name="radiance" value="1"/></emitter>
</scene>
"""


@pytest.fixture
def xml(tmp_path):
    p = tmp_path / "scene.xml"
    p.write_text(XML)
    return str(p)


def test_keyword_parameters_set_the_scene_defaults(xml):
    s = restir.load_scene(xml)
    assert (s.spp, s.camera.width) == (16, 32)
    s = restir.load_scene(xml, spp=4, res=8, albedo=0.25)     # numbers, as mi.load_file(path, **params)
    assert (s.spp, s.camera.width, s.camera.height) == (4, 8, 8)
    s = restir.load_scene(xml, res="12")                      # or strings
    assert s.camera.width == 12
    s = restir.load_scene(xml, {"spp": 2})                    # a dict of defines, values of any type
    assert s.spp == 2


@pytest.mark.parametrize("kw", [{"resx": 64}, {"width": 64}])
def test_unknown_parameters_are_errors(xml, kw):
    with pytest.raises(restir.SceneError, match=f"never uses '{next(iter(kw))}'"):
        restir.load_scene(xml, **kw)
    with pytest.raises(restir.SceneError, match="unknown parameter"):
        restir.load_scene("builtin:cornell-box", resx=64)


def test_dict_scenes_load():
    tree = builtin_scene("cornell-box", width=16, height=12)
    s = restir.load_scene(tree)
    assert (s.camera.width, s.camera.height) == (16, 12) and s.num_triangles > 0
    with pytest.raises(restir.SceneError):
        restir.load_scene(tree, spp=4)
    with pytest.raises(restir.SceneError):
        restir.load_scene(42)


def test_render_takes_the_common_settings_as_keywords():
    scene = restir.load_scene("builtin:cornell-box", width=8, height=8)
    r = restir.render(scene, spp=2, frames=3, seed=5, method="pt", max_depth=3)
    assert (r.stats["spp_per_frame"], r.stats["frames"], r.stats["max_depth"]) == (2, 3, 3)
    r2 = restir.render(scene, restir.RenderConfig(spp=2, frames=3, max_depth=3), seed=5)  # on top of a config
    assert np.array_equal(r.image, r2.image)
    with pytest.raises(restir.ConfigError, match="unknown render setting"):
        restir.render(scene, spp=1, candidates=4)


def test_results_are_short_to_print_and_show_inline(tmp_path):
    scene = restir.load_scene("builtin:cornell-box", width=8, height=8)
    r = restir.render(scene, spp=1)
    text = repr(r)
    assert len(text) < 200 and "cornell-box" in text and "8x8" in text
    png = r._repr_png_()
    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    restir.write_image(tmp_path / "a.npy", r)
    np.testing.assert_array_equal(np.load(tmp_path / "a.npy"), r.image)
    restir.write_image(str(tmp_path / "a.exr"), r.image)
    assert (tmp_path / "a.exr").stat().st_size > 0


def test_api_guide_example_runs(tmp_path, monkeypatch):
    """The example of docs/guide/python_api.md, run as written."""
    page = (pathlib.Path(__file__).resolve().parents[2] / "docs" / "guide" / "python_api.md").read_text()
    block = re.search(r"```python\n(import restir\n.*?)```", page, re.S).group(1)
    monkeypatch.chdir(tmp_path)
    env = {}
    exec(compile(block, "docs/guide/python_api.md", "exec"), env)
    assert env["result"].image.shape == (64, 64, 3) and (tmp_path / "cornell-box.exr").exists()
    assert env["di"].stats["method"] == "restir-di"


def test_rays_are_counted_per_stage_with_the_direct_light_component():
    """stats["rays"] is the sum of stats["rays_by_stage"], and a method with ReSTIR DI for direct
    light counts the component's rays (its stages "di.*") among its own."""
    scene = restir.load_scene("builtin:cornell-box", width=16, height=16)
    r = restir.render(scene, restir.RenderConfig(method="restir-pt", spp=1, frames=1, max_depth=3,
                                                 settings={"direct": "restir-di"}))
    by_stage = r.stats["rays_by_stage"]
    assert sum(by_stage.values()) == r.stats["rays"]
    # emission.rays camera rays per pixel (ReSTIR PT's default: 4), at every pixel in the first launch
    assert by_stage["gbuffer"] == 4 * 16 * 16
    assert by_stage["di.initial_temporal"] > 0 and by_stage["trace_temporal"] > 0
