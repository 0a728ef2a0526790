"""Scene-loader semantics that decide an image without any sampling: defaults Mitsuba 3 applies
when the file leaves something out. Deterministic (each value is Mitsuba 3.9.1's, read with its
own loader when the test was written)."""
import numpy as np

import restir


def _scene(shape_children: str) -> str:
    return f"""<scene version="3.0.0">
    <sensor type="perspective"><float name="fov" value="40"/><film type="hdrfilm"><integer name="width" value="4"/>
        <integer name="height" value="4"/></film></sensor>
    <shape type="rectangle">{shape_children}</shape>
</scene>"""


def _material(tmp_path, xml: str):
    (tmp_path / "scene.xml").write_text(xml)
    scene = restir.load_scene(str(tmp_path / "scene.xml"))
    return scene.materials[int(scene.tri_material[0])]


def test_shape_without_bsdf_is_grey_diffuse(tmp_path):
    m = _material(tmp_path, _scene(""))
    assert m.kind == "diffuse"
    np.testing.assert_array_equal(m.reflectance, [0.5, 0.5, 0.5])


def test_emitter_without_bsdf_reflects_nothing(tmp_path):
    # mi.load_dict({"type": "rectangle", "emitter": {"type": "area"}}).bsdf(): reflectance 0
    m = _material(tmp_path, _scene('<emitter type="area"><rgb name="radiance" value="1"/></emitter>'))
    assert m.kind == "diffuse"
    np.testing.assert_array_equal(m.reflectance, [0.0, 0.0, 0.0])


def test_emitter_keeps_a_given_bsdf(tmp_path):
    m = _material(tmp_path, _scene('<bsdf type="diffuse"><rgb name="reflectance" value="0.3"/></bsdf>'
                                   '<emitter type="area"><rgb name="radiance" value="1"/></emitter>'))
    np.testing.assert_allclose(m.reflectance, [0.3, 0.3, 0.3])
