"""Textured BSDF parameters: a bitmap on any parameter the loader reads as a spectrum reaches the
BSDFs through the one texture-or-constant lookup (scene_device.textured_material), and only that
parameter changes.

Each case loads a one-rectangle scene whose BSDF has a 2x2 raw (linear) PNG on one parameter,
uploads it as a render does, and reads `textured_material` on the device at each texel's centre, where
the bilinear lookup returns the texel exactly. Deterministic (no statistics): the looked-up values
must equal the texels to float32 rounding, and every other spectrum must keep its constant.
"""
import numpy as np
import pytest
import warp as wp

import restir
from restir.device.scene_device import SceneDevice, textured_material
from restir.scene.scene import TEXTURED_SPECTRA
from restir.scene.upload import DeviceScene

TEXELS = np.array([[[10, 200, 30], [250, 5, 90]],
                   [[60, 70, 240], [128, 255, 0]]], np.uint8)  # rows top to bottom
SPECTRA = TEXTURED_SPECTRA

SCENE = """<scene version="3.0.0">
    <sensor type="perspective"><float name="fov" value="40"/>
        <film type="hdrfilm"><integer name="width" value="4"/><integer name="height" value="4"/></film>
    </sensor>
    <shape type="rectangle"><bsdf type="{bsdf}">{extra}
        <texture type="bitmap" name="{name}"><string name="filename" value="tex.png"/>
            <boolean name="raw" value="true"/></texture>
    </bsdf></shape>
    <shape type="sphere"><point name="center" x="0" y="0" z="5"/><float name="radius" value="0.5"/>
        <emitter type="area"><rgb name="radiance" value="1"/></emitter></shape>
</scene>"""

# (bsdf, the XML parameter, the Material field it fills, extra XML)
CASES = [
    ("diffuse", "reflectance", "reflectance", ""),
    ("plastic", "diffuse_reflectance", "reflectance", ""),
    ("plastic", "specular_reflectance", "specular_reflectance", ""),
    ("roughplastic", "diffuse_reflectance", "reflectance", '<float name="alpha" value="0.3"/>'),
    ("conductor", "specular_reflectance", "specular_reflectance", '<rgb name="eta" value="0.2"/><rgb name="k" value="3"/>'),
    ("roughconductor", "specular_reflectance", "specular_reflectance",
     '<rgb name="eta" value="0.2"/><rgb name="k" value="3"/><float name="alpha" value="0.2"/>'),
    ("dielectric", "specular_reflectance", "specular_reflectance", ""),
    ("dielectric", "specular_transmittance", "specular_transmittance", ""),
    ("thindielectric", "specular_transmittance", "specular_transmittance", ""),
    ("roughdielectric", "specular_reflectance", "specular_reflectance", '<float name="alpha" value="0.2"/>'),
]


@wp.kernel
def lookup_kernel(scene: SceneDevice, uvs: wp.array(dtype=wp.vec2), out: wp.array(dtype=wp.vec3, ndim=2)):
    i = wp.tid()
    m = textured_material(scene, 0, uvs[i])
    out[i, 0] = m.reflectance
    out[i, 1] = m.specular_reflectance
    out[i, 2] = m.specular_transmittance


@pytest.mark.parametrize("bsdf,name,field,extra", CASES, ids=[f"{c[0]}.{c[1]}" for c in CASES])
def test_texture_reaches_its_parameter_only(tmp_path, device, bsdf, name, field, extra):
    from PIL import Image

    Image.fromarray(TEXELS).save(tmp_path / "tex.png")
    (tmp_path / "scene.xml").write_text(SCENE.format(bsdf=bsdf, name=name, extra=extra))
    scene = restir.load_scene(str(tmp_path / "scene.xml"))
    ds = DeviceScene(scene, device, "warp")
    rect = scene.materials[int(scene.tri_material[0])]
    assert field in rect.textures, rect.textures
    constants = {k: np.asarray(getattr(rect, k), np.float32) for k in SPECTRA}

    # texel centres: uv (0,0) is the top-left corner of the first texel
    uvs = np.array([[(x + 0.5) / 2, (y + 0.5) / 2] for y in range(2) for x in range(2)], np.float32)
    out = wp.zeros((4, 3), dtype=wp.vec3, device=device)
    wp.launch(lookup_kernel, dim=4, inputs=[ds.scene, wp.array(uvs, dtype=wp.vec2, device=device), out],
              device=device)
    got = out.numpy().astype(np.float64)
    want = TEXELS.reshape(4, 3) / 255.0
    col = SPECTRA.index(field)
    np.testing.assert_allclose(got[:, col], want, rtol=0, atol=1e-6, err_msg=f"{bsdf}.{name} -> {field}")
    for k, c in enumerate(SPECTRA):
        if c != field:
            np.testing.assert_array_equal(got[:, k], np.broadcast_to(constants[c].astype(np.float64), (4, 3)), err_msg=c)
