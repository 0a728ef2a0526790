"""Opacity masks (Mitsuba 3's `mask`, loaded by scene.py's `mask`; bsdf.py's null lobe): what the
loader reads and refuses, the opacity a hit sees, and that opacity 1 changes nothing.

Deterministic (no statistics). The null lobe's probability and weight are test_bsdf's
(test_mask_null_lobe); the rendered comparison with Mitsuba 3 is tests/integration/test_mitsuba.py
("masks"); unbiasedness of reuse across masked surfaces is in the three matrices.
"""
import numpy as np
import pytest
import warp as wp

import restir
from restir.device.bounce import material_at, shading_frame
from restir.device.bsdf import bsdf_lobes
from restir.device.intersect import surface_at
from restir.device.scene_device import SceneDevice
from restir.device.types import LOBE_DIFFUSE_REFLECTION, LOBE_NULL
from restir.scene.errors import SceneError
from restir.scene.upload import DeviceScene
from tests.scenes import write_scene

DIFFUSE = '<bsdf type="twosided"><bsdf type="diffuse"/></bsdf>'
ONE_SIDED = '<bsdf type="diffuse"/>'


def mask_xml(opacity='<texture name="opacity" type="bitmap"><string name="filename" value="h.png"/></texture>',
             inner=DIFFUSE):
    return f'<bsdf type="mask">{opacity}{inner}</bsdf>'


# ----------------------------------------------------------------------------- the loader
def test_bitterlis_masks_load(tmp_path):
    """The three forms of Bitterli's scenes: a texture (the living room's leaves, the bathroom's
    rug), a number (the kitchen's blinds), and the default 0.5."""
    img = np.full((2, 2, 3), 200, np.uint8)
    sc = restir.load_scene(write_scene(tmp_path, mask_xml(), img))
    (m,) = sc.materials
    assert m.masked and m.twosided and m.kind == "diffuse" and m.opacity == 1.0
    assert sc.textures[m.textures["opacity"]].kind == "bitmap"
    (m,) = restir.load_scene(write_scene(tmp_path, mask_xml('<float name="opacity" value="0.612066"/>'))).materials
    assert m.masked and m.opacity == pytest.approx(0.612066) and "opacity" not in m.textures
    (m,) = restir.load_scene(write_scene(tmp_path, mask_xml(""))).materials
    assert m.masked and m.opacity == 0.5
    (m,) = restir.load_scene(write_scene(tmp_path, mask_xml('<float name="opacity" value="1.7"/>'))).materials
    assert m.opacity == 1.0  # clipped, as Mitsuba's eval_opacity does


def test_an_alpha_channel_is_dropped_and_said(tmp_path):
    """Mitsuba 3 reads a mask's RGBA bitmap as RGB (bitmap.cpp drops alpha): so does restir,
    with a warning, since Bitterli's living room means the alpha (its leaf.png is near white
    where alpha is 0)."""
    from restir.scene.errors import SceneWarning

    rgba = np.zeros((2, 2, 4), np.uint8)
    rgba[..., :3], rgba[..., 3] = 250, 0
    from PIL import Image

    path = write_scene(tmp_path, mask_xml())
    Image.fromarray(rgba, mode="RGBA").save(tmp_path / "h.png")
    with pytest.warns(SceneWarning, match="alpha channel, which is dropped"):
        sc = restir.load_scene(path)
    assert sc.textures[0].image.shape[-1] == 3 and sc.textures[0].image.min() > 0.9  # the RGB, not the alpha


def test_a_v05_spectrum_opacity_loads(tmp_path):
    """The kitchen's `<spectrum name="opacity" value="0.612066"/>` in a Mitsuba 0.5 file."""
    (tmp_path / "s.xml").write_text("""<scene version="0.5.0">
        <sensor type="perspective"><float name="fov" value="40"/><film type="hdrfilm"><integer name="width" value="4"/>
            <integer name="height" value="4"/></film></sensor>
        <bsdf type="mask" id="Blinds"><spectrum name="opacity" value="0.612066"/>
            <bsdf type="twosided"><bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.5, 0.4"/></bsdf></bsdf>
        </bsdf>
        <shape type="rectangle"><ref id="Blinds"/></shape>
    </scene>""")
    (m,) = restir.load_scene(str(tmp_path / "s.xml")).materials
    assert m.masked and m.opacity == pytest.approx(0.612066)


@pytest.mark.parametrize("bsdf,message", [
    (mask_xml(inner=mask_xml()), "nested mask"),
    (f'<bsdf type="twosided">{mask_xml(inner=ONE_SIDED)}</bsdf>', "mask must be the outermost"),
    ('<bsdf type="bumpmap"><texture name="map" type="bitmap"><string name="filename" value="h.png"/></texture>'
     f'{mask_xml()}</bsdf>', "mask must be the outermost"),
    (mask_xml(inner=""), "exactly one nested BSDF"),
    (mask_xml(inner=DIFFUSE + DIFFUSE), "exactly one nested BSDF"),
    (mask_xml('<rgb name="opacity" value="0.2, 0.5, 0.9"/>'), "one number"),
])
def test_bad_masks_are_refused(tmp_path, bsdf, message):
    with pytest.raises(SceneError, match=message):
        restir.load_scene(write_scene(tmp_path, bsdf, np.full((2, 2, 3), 100, np.uint8)))


# ----------------------------------------------------------------------------- the device
@wp.kernel
def opacity_kernel(scene: SceneDevice, b: wp.array(dtype=wp.vec2), opacity: wp.array(dtype=float),
                   lobes: wp.array(dtype=int)):
    i = wp.tid()
    hit = surface_at(scene, 0, b[i][0], b[i][1], 1.0)
    mat = material_at(scene, hit, shading_frame(scene, hit, hit.ns))
    opacity[i] = mat.opacity
    lobes[i] = bsdf_lobes(mat)


def opacities(path, bary):
    ds = DeviceScene(restir.load_scene(path), "cpu", "warp")
    out = wp.zeros(len(bary), dtype=float, device="cpu")
    lobes = wp.zeros(len(bary), dtype=int, device="cpu")
    wp.launch(opacity_kernel, dim=len(bary), inputs=[ds.scene, wp.array(np.asarray(bary, np.float32), dtype=wp.vec2,
                                                                        device="cpu"), out, lobes], device="cpu")
    return out.numpy(), lobes.numpy()


def test_a_hit_sees_the_textures_luminance(tmp_path):
    """A uniform coloured bitmap: every hit's opacity is the luminance of its linearized texel
    (Mitsuba's eval_1 of an 8-bit sRGB image), with the exact Rec. 709 weights."""
    rgb = np.array([200, 40, 120], np.uint8)
    lin = np.array([((c / 255 + 0.055) / 1.055) ** 2.4 for c in rgb])
    expected = float(np.dot([0.212671, 0.715160, 0.072169], lin))
    got, lobes = opacities(write_scene(tmp_path, mask_xml(), np.tile(rgb, (2, 2, 1))), [[0.2, 0.3], [0.6, 0.1]])
    np.testing.assert_allclose(got, expected, rtol=2e-6)
    assert np.all(lobes == LOBE_DIFFUSE_REFLECTION | LOBE_NULL)
    got, lobes = opacities(write_scene(tmp_path, DIFFUSE), [[0.2, 0.3]])
    assert got[0] == 1.0 and lobes[0] == LOBE_DIFFUSE_REFLECTION


def test_an_opaque_mask_renders_the_same_image(tmp_path):
    """opacity 1: the null lobe is never chosen and every product with the opacity is exact, so
    the image is bit-identical to the unmasked scene's (the same random numbers throughout)."""
    from tests.data.feature_scene import write_mask_scene

    path = write_mask_scene(str(tmp_path / "m"))
    text = open(path).read()
    import re

    opaque = re.sub(r'<bsdf type="mask">(<float name="opacity" value="[0-9.]+"/>|\s*<texture name="opacity".*?</texture>)',
                    '<bsdf type="mask"><float name="opacity" value="1"/>', text, flags=re.S)
    plain = re.sub(r'<bsdf type="mask">(<float name="opacity" value="[0-9.]+"/>|\s*<texture name="opacity".*?</texture>)',
                   '<bsdf type="twosided_placeholder">', text, flags=re.S)
    assert opaque.count('value="1"/>') >= 5 and plain.count("twosided_placeholder") == 5
    # the unmasked twin: each mask's element dropped around its BSDF
    plain = re.sub(r'<bsdf type="twosided_placeholder">(.*?)\n(\s*)</bsdf>\n(\s*)</shape>',
                   lambda mt: mt.group(1) + "\n" + mt.group(3) + "</shape>", plain, flags=re.S)
    assert "mask" not in plain and "placeholder" not in plain
    images = []
    for name, xml in (("opaque.xml", opaque), ("plain.xml", plain)):
        (tmp_path / "m" / name).write_text(xml)
        sc = restir.load_scene(str(tmp_path / "m" / name))
        images.append(restir.render(sc, restir.RenderConfig(spp=2, frames=1, width=24, height=18, max_depth=5,
                                                            seed=3)).image)
    assert np.array_equal(images[0], images[1])
