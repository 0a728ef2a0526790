"""Textures (device/textures.py, loaded by scene/textures.py): checkerboard cells, to_uv, and the
bitmap's filter and wrap modes, read on the device at points whose values are known by hand.

Deterministic (no statistics). The expected values are written out per point, not recomputed by
a second implementation; the Mitsuba 3 comparison of a rendered texture scene is in
tests/integration/test_mitsuba.py ("textures").
"""
import numpy as np
import pytest
import warp as wp

import restir
from restir.device.textures import Texture, texture_eval
from restir.scene.errors import SceneError
from restir.scene.upload import DeviceScene

# a 3 x 2 texel bitmap, raw (linear): texel (x, y) has red = x, green = y (in 1/255 units x 50)
TEXELS = np.array([[[0, 0, 9], [50, 0, 9], [100, 0, 9]],
                   [[0, 50, 9], [50, 50, 9], [100, 50, 9]]], np.uint8)


def scene_with(tmp_path, texture_xml: str) -> DeviceScene:
    from PIL import Image

    Image.fromarray(TEXELS).save(tmp_path / "t.png")
    xml = f"""<scene version="3.0.0">
        <sensor type="perspective"><float name="fov" value="40"/><film type="hdrfilm"><integer name="width" value="4"/>
            <integer name="height" value="4"/></film></sensor>
        <shape type="rectangle"><bsdf type="diffuse">{texture_xml}</bsdf></shape>
    </scene>"""
    (tmp_path / "s.xml").write_text(xml)
    return DeviceScene(restir.load_scene(str(tmp_path / "s.xml")), "cpu", "warp")


@wp.kernel
def eval_kernel(textures: wp.array(dtype=Texture), texels: wp.array(dtype=wp.vec3), uvs: wp.array(dtype=wp.vec2),
                out: wp.array(dtype=wp.vec3)):
    i = wp.tid()
    out[i] = texture_eval(textures, texels, 0, uvs[i])


def lookup(ds: DeviceScene, uvs) -> np.ndarray:
    uvs = np.asarray(uvs, np.float32)
    out = wp.zeros(len(uvs), dtype=wp.vec3, device="cpu")
    wp.launch(eval_kernel, dim=len(uvs), inputs=[ds.scene.textures, ds.scene.tex_pixels,
                                                 wp.array(uvs, dtype=wp.vec2, device="cpu"), out], device="cpu")
    return out.numpy()


def texel(x, y):
    return TEXELS[y, x].astype(np.float64) / 255.0


BITMAP = ('<texture name="reflectance" type="bitmap"><string name="filename" value="t.png"/>'
          '<boolean name="raw" value="true"/>{extra}</texture>')


def test_checkerboard_cells_and_to_uv(tmp_path):
    ds = scene_with(tmp_path, '<texture name="reflectance" type="checkerboard"><rgb name="color0" value="1, 0, 0"/>'
                              '<rgb name="color1" value="0, 0, 1"/><transform name="to_uv"><scale x="2" y="4"/>'
                              '</transform></texture>')
    c0, c1 = [1, 0, 0], [0, 0, 1]
    # (u, v) -> to_uv (2u, 4v): color0 where both fractional parts exceed 1/2 or neither does (the
    # values Mitsuba 3.9.1's checkerboard returns at these points)
    cases = [((0.1, 0.05), c0),   # (0.2, 0.2): both low
             ((0.3, 0.05), c1),   # (0.6, 0.2)
             ((0.1, 0.15), c1),   # (0.2, 0.6)
             ((0.3, 0.15), c0),   # (0.6, 0.6): both high
             ((0.6, 0.3), c0),    # (1.2, 1.2): the pattern repeats
             ((-0.1, 0.05), c1)]  # (-0.2, 0.2): frac(-0.2) = 0.8
    got = lookup(ds, [c[0] for c in cases])
    np.testing.assert_array_equal(got, np.array([c[1] for c in cases], np.float32))


def test_checkerboard_defaults_and_mean(tmp_path):
    ds = scene_with(tmp_path, '<texture name="reflectance" type="checkerboard"/>')
    np.testing.assert_allclose(lookup(ds, [(0.25, 0.25), (0.75, 0.25)]), [[0.4] * 3, [0.2] * 3], rtol=1e-6)
    assert ds.host.textures[0].mean() == pytest.approx(0.3)


@pytest.mark.parametrize("wrap,expect", [
    # u = -0.1 is texel x = floor(-0.3) = -1; u = 1.2 is x = floor(3.6) = 3 (width 3); v = 0.25 is y = 0
    ("repeat", [(2, 0), (0, 0)]),
    ("mirror", [(0, 0), (2, 0)]),
    ("clamp", [(0, 0), (2, 0)]),
])
def test_nearest_filter_and_wrap_modes(tmp_path, wrap, expect):
    ds = scene_with(tmp_path, BITMAP.format(extra=f'<string name="filter_type" value="nearest"/>'
                                                  f'<string name="wrap_mode" value="{wrap}"/>'))
    np.testing.assert_allclose(lookup(ds, [(-0.1, 0.25), (1.2, 0.25)]), [texel(*e) for e in expect], atol=1e-6)


def test_wrap_modes_beyond_one_period(tmp_path):
    # u = 1.5 and 1.84 are x = floor(4.5) = 4 and floor(5.52) = 5 (width 3):
    # repeat -> 1, 2; mirror -> 2 * 3 - 1 - x = 1, 0; clamp -> 2, 2
    for wrap, xs in (("repeat", (1, 2)), ("mirror", (1, 0)), ("clamp", (2, 2))):
        ds = scene_with(tmp_path, BITMAP.format(extra=f'<string name="filter_type" value="nearest"/>'
                                                      f'<string name="wrap_mode" value="{wrap}"/>'))
        np.testing.assert_allclose(lookup(ds, [(1.5, 0.75), (1.84, 0.75)]), [texel(x, 1) for x in xs], atol=1e-6,
                                   err_msg=wrap)


def test_bilinear_default_and_to_uv_offset(tmp_path):
    ds = scene_with(tmp_path, BITMAP.format(extra=""))
    # texel centres are exact; halfway between texels (1, 0) and (2, 0) is their average
    np.testing.assert_allclose(lookup(ds, [(1.5 / 3, 0.25), (2.0 / 3, 0.25)]),
                               [texel(1, 0), 0.5 * (texel(1, 0) + texel(2, 0))], atol=1e-6)
    # to_uv's translation: (u, v) -> (u + 1/3, v + 1/2) moves one texel right and one down
    ds = scene_with(tmp_path, BITMAP.format(
        extra='<transform name="to_uv"><translate x="0.33333334" y="0.5"/></transform>'))
    np.testing.assert_allclose(lookup(ds, [(0.5 / 3, 0.25)]), [texel(1, 1)], atol=1e-5)


def test_an_offset_in_a_3x3_to_uv_is_ignored_with_a_warning(tmp_path):
    # Mitsuba 3.9.1 ignores the third column of a 3x3 <matrix> (its uv is (u, v, 0, 1)): so do we, and say so
    with pytest.warns(restir.SceneWarning, match="to_uv"):
        ds = scene_with(tmp_path, BITMAP.format(
            extra='<transform name="to_uv"><matrix value="1 0 0.33333334  0 1 0.5  0 0 1"/></transform>'))
    np.testing.assert_allclose(lookup(ds, [(0.5 / 3, 0.25)]), [texel(0, 0)], atol=1e-5)


@pytest.mark.parametrize("extra,message", [
    ('<string name="filter_type" value="ewa"/>', "filter_type 'ewa' is not supported"),
    ('<string name="wrap_mode" value="zero"/>', "wrap_mode 'zero' is not supported"),
])
def test_unsupported_modes_are_errors(tmp_path, extra, message):
    with pytest.raises(SceneError, match=message):
        scene_with(tmp_path, BITMAP.format(extra=extra))


def test_a_texture_inside_a_checkerboard_is_an_error(tmp_path):
    with pytest.raises(SceneError, match="must be an RGB value here, not a texture"):
        scene_with(tmp_path, '<texture name="reflectance" type="checkerboard">'
                             '<texture name="color0" type="bitmap"><string name="filename" value="t.png"/></texture>'
                             '</texture>')
