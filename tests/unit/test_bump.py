"""Bump maps (device/bump.py, loaded by scene.py's `bumpmap`): the height gradient, the tilted
normal and its flip, the BSDF factor, and what the loader accepts and refuses.

Deterministic (no statistics). Expected normals and factors are written out by hand for ramps
whose gradient is known; the gradient itself is checked against finite differences of the
texture lookup the renderer uses (texture_eval). The rendered comparison with Mitsuba 3 is
tests/integration/test_mitsuba.py ("bumps"); the BSDF with a bump factor is in test_bsdf's
chi-square cases; unbiasedness of reuse across bump-mapped surfaces in the three matrices.
"""
import math

import numpy as np
import pytest
import warp as wp

import restir
from restir.device.bounce import material_at, shading_frame
from restir.device.bsdf import bsdf_eval, bsdf_pdf, bsdf_sample
from restir.device.intersect import surface_at
from restir.device.sampling import to_local
from restir.device.scene_device import SceneDevice
from restir.device.textures import Texture, scalar_of, texture_eval, texture_grad1
from restir.scene.errors import SceneError, SceneWarning
from restir.scene.upload import DeviceScene
from tests.scenes import write_scene


def device_scene(path) -> DeviceScene:
    return DeviceScene(restir.load_scene(path), "cpu", "warp")


def bump_xml(extra="", inner='<bsdf type="diffuse"/>', tex_extra='<boolean name="raw" value="true"/>'):
    return (f'<bsdf type="bumpmap"><texture name="map" type="bitmap"><string name="filename" value="h.png"/>'
            f'{tex_extra}</texture>{extra}{inner}</bsdf>')


# ----------------------------------------------------------------------------- the gradient
@wp.kernel
def grad_kernel(textures: wp.array(dtype=Texture), texels: wp.array(dtype=wp.vec3), uvs: wp.array(dtype=wp.vec2),
                h: float, grad: wp.array(dtype=wp.vec2), fd: wp.array(dtype=wp.vec2)):
    i = wp.tid()
    uv = uvs[i]
    grad[i] = texture_grad1(textures, texels, 0, uv)
    du = wp.vec2(h, 0.0)
    dv = wp.vec2(0.0, h)
    fd[i] = wp.vec2((scalar_of(texture_eval(textures, texels, 0, uv + du)) -
                     scalar_of(texture_eval(textures, texels, 0, uv - du))) / (2.0 * h),
                    (scalar_of(texture_eval(textures, texels, 0, uv + dv)) -
                     scalar_of(texture_eval(textures, texels, 0, uv - dv))) / (2.0 * h))


def test_gradient_is_the_derivative_of_the_lookup(tmp_path):
    """A coloured 5 x 3 bitmap (non-square: Mitsuba's own product differs from the chain rule
    there), rotated and scaled by to_uv, wrapped: texture_grad1 against central differences of
    texture_eval's luminance, at points away from the texel-centre lines where the bilinear
    interpolant's derivative jumps."""
    rng = np.random.default_rng(3)
    img = rng.integers(0, 256, (3, 5, 3)).astype(np.uint8)
    path = write_scene(tmp_path, bump_xml(tex_extra='<boolean name="raw" value="true"/><transform name="to_uv">'
                                          '<rotate z="1" angle="30"/><scale x="1.7" y="0.6"/></transform>'), img)
    ds = device_scene(path)
    uvs = rng.uniform(-1.0, 2.0, (400, 2)).astype(np.float32)
    grad = wp.zeros(len(uvs), dtype=wp.vec2, device="cpu")
    fd = wp.zeros(len(uvs), dtype=wp.vec2, device="cpu")
    h = 1e-3
    wp.launch(grad_kernel, dim=len(uvs), inputs=[ds.scene.textures, ds.scene.tex_pixels,
                                                 wp.array(uvs, dtype=wp.vec2, device="cpu"), h, grad, fd], device="cpu")
    g, f = grad.numpy(), fd.numpy()
    # texel-space position of each point: keep those whose finite-difference stencil stays inside
    # one bilinear cell (the stencil moves at most |to_uv| * h * res texels)
    m = np.array([[math.cos(math.radians(30)), -math.sin(math.radians(30))],
                  [math.sin(math.radians(30)), math.cos(math.radians(30))]]) * np.array([[1.7], [0.6]])
    q = uvs @ m.T * np.array([5, 3]) - 0.5
    frac = q - np.floor(q)
    ok = np.all((frac > 0.02) & (frac < 0.98), axis=1)
    assert ok.sum() > 300
    np.testing.assert_allclose(g[ok], f[ok], rtol=2e-3, atol=2e-3 * np.abs(f[ok]).max())
    assert np.abs(g[ok]).max() > 1.0  # a real gradient, not zeros on both sides


def test_nearest_filtering_has_no_gradient(tmp_path):
    img = np.random.default_rng(1).integers(0, 256, (4, 4)).astype(np.uint8)
    path = write_scene(tmp_path, bump_xml(tex_extra='<string name="filter_type" value="nearest"/>'), img, mode="L")
    with pytest.warns(SceneWarning, match="gradient 0"):
        ds = device_scene(path)
    grad = wp.zeros(1, dtype=wp.vec2, device="cpu")
    wp.launch(grad_kernel, dim=1, inputs=[ds.scene.textures, ds.scene.tex_pixels,
                                          wp.array(np.array([[0.3, 0.6]], np.float32), dtype=wp.vec2, device="cpu"),
                                          1e-3, grad, wp.zeros(1, dtype=wp.vec2, device="cpu")], device="cpu")
    assert np.all(grad.numpy() == 0.0)


# ----------------------------------------------------------------------------- the tilted frame
@wp.kernel
def shade_kernel(scene: SceneDevice, tri: int, b: wp.vec2, wi: wp.vec3, n: wp.array(dtype=wp.vec3),
                 n0: wp.array(dtype=wp.vec3), alpha2: wp.array(dtype=float), wo: wp.array(dtype=wp.vec3),
                 f: wp.array(dtype=wp.vec3), pdf: wp.array(dtype=float)):
    hit = surface_at(scene, tri, b[0], b[1], 1.0)
    frame = shading_frame(scene, hit, wi)
    mat = material_at(scene, hit, frame)
    n[0] = frame.n
    n0[0] = mat.bump_n0
    alpha2[0] = mat.bump_alpha2
    i = wp.tid()
    w = to_local(frame, wo[i])
    f[i] = bsdf_eval(mat, to_local(frame, wi), w)
    pdf[i] = bsdf_pdf(mat, to_local(frame, wi), w)


def shade(ds, wi, wos=((0.0, 0.0, 1.0),)):
    outs = [wp.zeros(1, dtype=wp.vec3, device="cpu"), wp.zeros(1, dtype=wp.vec3, device="cpu"),
            wp.zeros(1, dtype=float, device="cpu")]
    wos = np.asarray(wos, np.float32)
    wos = wos / np.linalg.norm(wos, axis=1, keepdims=True)
    f = wp.zeros(len(wos), dtype=wp.vec3, device="cpu")
    pdf = wp.zeros(len(wos), dtype=float, device="cpu")
    wi = np.asarray(wi, np.float32) / np.linalg.norm(wi)
    # triangle 0 of the rectangle, at its centroid (a bilinear cell's interior for the ramp below)
    wp.launch(shade_kernel, dim=len(wos), inputs=[ds.scene, 0, wp.vec2(1 / 3, 1 / 3), wp.vec3(*wi), *outs,
                                                  wp.array(wos, dtype=wp.vec3, device="cpu"), f, pdf], device="cpu")
    return outs[0].numpy()[0], outs[1].numpy()[0], float(outs[2].numpy()[0]), f.numpy(), pdf.numpy()


# A ramp in u: a 4 x 1 raw grey bitmap 0, a, 2a, 3a (a = 60 / 255); bilinear, clamped, so between
# texel centres its height h(u) has dh/du = a * 4 (texels per unit u) everywhere inside.
RAMP = np.array([[0, 60, 120, 180]], np.uint8)
RAMP_SLOPE = 60 / 255 * 4


def test_a_ramp_tilts_the_normal_by_hand(tmp_path):
    """On the rectangle dp/du = (2, 0, 0), dp/dv = (0, 2, 0), ns = (0, 0, 1); with g = scale * dh/du:
    dp/du' = (2, 0, g), so n = normalize((2, 0, g) x (0, 2, 0)) = normalize(-g, 0, 2)."""
    scale = 1.5
    path = write_scene(tmp_path, bump_xml(f'<float name="scale" value="{scale}"/>',
                                          tex_extra='<boolean name="raw" value="true"/>'
                                          '<string name="wrap_mode" value="clamp"/>'), RAMP, mode="L")
    n, n0, alpha2, _, _ = shade(device_scene(path), (0.0, 0.3, 1.0))
    g = scale * RAMP_SLOPE
    expect = np.array([-g, 0.0, 2.0]) / math.hypot(g, 2.0)
    np.testing.assert_allclose(n, expect, atol=2e-5)
    # ns in the tilted frame has cosine n . ns; Estevez's alpha^2 = min(tan^2 / 8, 1)
    assert n0[2] == pytest.approx(2.0 / math.hypot(g, 2.0), abs=2e-6)
    assert alpha2 == pytest.approx(min((g / 2.0) ** 2 / 8.0, 1.0), rel=1e-4)


def test_an_invalid_normal_is_mirrored_about_ns(tmp_path):
    """wi above ns but below the tilted n: Mitsuba's flip_invalid_normals mirrors n about ns,
    (-g, 0, 2) -> (g, 0, 2); with the flip off the tilted normal stays."""
    xml = bump_xml('<float name="scale" value="1.5"/>{}', tex_extra='<boolean name="raw" value="true"/>'
                   '<string name="wrap_mode" value="clamp"/>')
    g = 1.5 * RAMP_SLOPE
    wi = (1.0, 0.0, 0.15)  # 0.15 > 0 = above ns; its dot with (-g, 0, 2) is negative
    assert np.dot(wi, (-g, 0, 2)) < 0
    for flip, expect in (("", (g, 0.0, 2.0)), ('<boolean name="flip_invalid_normals" value="false"/>', (-g, 0.0, 2.0))):
        sub = tmp_path / str(len(flip))
        sub.mkdir()
        n, *_ = shade(device_scene(write_scene(sub, xml.format(flip), RAMP, mode="L")), wi)
        np.testing.assert_allclose(n, np.array(expect) / math.hypot(g, 2.0), atol=2e-5)


def test_the_bump_factor_of_eval_and_pdf(tmp_path):
    """A diffuse bumped by the ramp: wo between the two surfaces (above n, below ns, or the
    reverse) carries nothing, pdf included; elsewhere eval is the diffuse value in the tilted
    frame times Estevez's term 2 / (1 + sqrt(1 + alpha^2 tan^2(wo, ns))), and 1 with the term off."""
    g = 1.5 * RAMP_SLOPE
    n = np.array([-g, 0.0, 2.0]) / math.hypot(g, 2.0)
    wos = [(0.0, 0.3, 1.0), (-1.0, 0.0, -0.1), (1.0, 0.0, 0.1), (-0.5, 0.5, 0.6)]
    # (-1, 0, -0.1): below ns, above n; (1, 0, 0.1): above ns, below n
    for wo, between in zip(wos, (False, True, True, False)):
        assert (np.dot(wo, n) * wo[2] <= 0) == between
    for shadowing in (True, False):
        sub = tmp_path / str(shadowing)
        sub.mkdir()
        off = "" if shadowing else '<boolean name="use_shadowing_function" value="false"/>'
        path = write_scene(sub, bump_xml(f'<float name="scale" value="1.5"/>{off}',
                                         inner='<bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf>',
                                         tex_extra='<boolean name="raw" value="true"/><string name="wrap_mode" '
                                         'value="clamp"/>'), RAMP, mode="L")
        _, _, alpha2, f, pdf = shade(device_scene(path), (0.0, 0.3, 1.0), wos)
        for i, wo in enumerate(wos):
            wo = np.array(wo) / np.linalg.norm(wo)
            if np.dot(wo, n) * wo[2] <= 0:
                assert np.all(f[i] == 0) and pdf[i] == 0
                continue
            cos_n, cos_s = np.dot(wo, n), wo[2]
            term = 2 / (1 + math.sqrt(1 + (g / 2) ** 2 / 8 * (1 - cos_s ** 2) / cos_s ** 2)) if shadowing else 1.0
            assert alpha2 == (pytest.approx(min((g / 2) ** 2 / 8, 1.0), rel=1e-4) if shadowing else 0.0)
            np.testing.assert_allclose(f[i], 0.5 / math.pi * cos_n * term, rtol=1e-4)
            assert pdf[i] == pytest.approx(cos_n / math.pi, rel=1e-4)


@wp.kernel
def delta_kernel(scene: SceneDevice, wi: wp.vec3, u: wp.array(dtype=wp.vec2), wo: wp.array(dtype=wp.vec3),
                 weight: wp.array(dtype=wp.vec3), valid: wp.array(dtype=int), n: wp.array(dtype=wp.vec3)):
    i = wp.tid()
    hit = surface_at(scene, 0, 1.0 / 3.0, 1.0 / 3.0, 1.0)
    frame = shading_frame(scene, hit, wi)
    mat = material_at(scene, hit, frame)
    s = bsdf_sample(mat, to_local(frame, wi), 0.5, u[i])
    wo[i] = frame.s * s.wo[0] + frame.t * s.wo[1] + frame.n * s.wo[2]
    weight[i] = s.weight
    valid[i] = s.valid
    n[i] = frame.n


def test_a_bumped_mirror_reflects_about_the_tilted_normal(tmp_path):
    """A delta lobe: the mirror direction of the tilted normal, its weight times the bump
    factor, and invalid where that direction falls between the two surfaces."""
    path = write_scene(tmp_path, bump_xml('<float name="scale" value="1.5"/>', inner='<bsdf type="conductor">'
                                          '<rgb name="eta" value="0"/><rgb name="k" value="1e6"/></bsdf>',
                                          tex_extra='<boolean name="raw" value="true"/><string name="wrap_mode" '
                                          'value="clamp"/>'), RAMP, mode="L")
    ds = device_scene(path)
    g = 1.5 * RAMP_SLOPE
    n = np.array([-g, 0.0, 2.0]) / math.hypot(g, 2.0)
    for wi, valid_expected in (((0.0, 0.2, 1.0), True), ((1.0, 0.0, 0.8), False)):
        wi = np.array(wi) / np.linalg.norm(wi)
        arrs = [wp.zeros(1, dtype=t, device="cpu") for t in (wp.vec3, wp.vec3, int, wp.vec3)]
        wp.launch(delta_kernel, dim=1, inputs=[ds.scene, wp.vec3(*wi), wp.array(np.full((1, 2), 0.5, np.float32),
                                               dtype=wp.vec2, device="cpu"), *arrs], device="cpu")
        wo, weight, valid, nn = (a.numpy()[0] for a in arrs)
        np.testing.assert_allclose(nn, n, atol=2e-5)
        mirror = 2 * np.dot(wi, n) * n - wi
        assert (mirror[2] * np.dot(mirror, n) > 0) == valid_expected
        assert bool(valid) == valid_expected
        if valid_expected:
            np.testing.assert_allclose(wo, mirror, atol=1e-5)
            tan2 = (1 - mirror[2] ** 2) / mirror[2] ** 2
            term = 2 / (1 + math.sqrt(1 + min((g / 2) ** 2 / 8, 1) * tan2))
            np.testing.assert_allclose(weight, term, rtol=1e-4)  # a perfect mirror: Fresnel 1


# ----------------------------------------------------------------------------- the loader
HEIGHT = np.full((2, 2), 128, np.uint8)


@pytest.mark.parametrize("bsdf,message", [
    ('<bsdf type="twosided">{}</bsdf>'.format(bump_xml()), "bumpmap inside a twosided"),
    (bump_xml(inner=bump_xml()), "nested bumpmap"),
    ('<bsdf type="bumpmap"><bsdf type="diffuse"/></bsdf>', "exactly one nested BSDF and one texture"),
    ('<bsdf type="bumpmap"><texture name="map" type="bitmap"><string name="filename" value="h.png"/></texture></bsdf>',
     "exactly one nested BSDF and one texture"),
    ('<bsdf type="bumpmap"><texture name="a" type="bitmap"><string name="filename" value="h.png"/></texture>'
     '<texture name="b" type="bitmap"><string name="filename" value="h.png"/></texture><bsdf type="diffuse"/></bsdf>',
     "exactly one nested BSDF and one texture"),
    ('<bsdf type="bumpmap"><texture name="map" type="checkerboard"/><bsdf type="diffuse"/></bsdf>', "checkerboard"),
])
def test_bad_bump_maps_are_refused(tmp_path, bsdf, message):
    with pytest.raises(SceneError, match=message):
        restir.load_scene(write_scene(tmp_path, bsdf, HEIGHT, mode="L"))


def test_the_loaded_bump_map(tmp_path):
    sc = restir.load_scene(write_scene(tmp_path, bump_xml('<float name="scale" value="0.25"/>',
                                                          inner='<bsdf type="twosided"><bsdf type="diffuse"/></bsdf>'),
                                       HEIGHT, mode="L"))
    (m,) = sc.materials
    assert m.twosided and m.kind == "diffuse"
    assert (m.bump.scale, m.bump.flip_invalid_normals, m.bump.use_shadowing_function) == (0.25, True, True)
    assert sc.textures[m.bump.texture].kind == "bitmap"


BITTERLI = ('<bsdf type="bumpmap"><texture name="map" type="bitmap"><string name="filename" value="h.png"/></texture>'
            '<bsdf type="twosided" id="floor"><bsdf type="diffuse"/></bsdf></bsdf>')


def test_bitterlis_unreferenced_wrapper_is_not_applied_and_said(tmp_path):
    """Shapes that refer to the BSDF inside a top-level bumpmap get it without the bump, as in
    Mitsuba 3: loaded so, with a warning naming the BSDF."""
    path = write_scene(tmp_path, '<ref id="floor"/>', HEIGHT, mode="L", before=BITTERLI)
    with pytest.warns(SceneWarning, match="bumpmap is not applied: shapes refer to the BSDF 'floor'"):
        sc = restir.load_scene(path)
    assert [m.bump for m in sc.materials] == [None]


def test_a_referenced_wrapper_is_applied_without_a_warning(tmp_path, recwarn):
    xml = BITTERLI.replace('<bsdf type="bumpmap">', '<bsdf type="bumpmap" id="bumped">')
    path = write_scene(tmp_path, '<ref id="bumped"/>', HEIGHT, mode="L", before=xml)
    sc = restir.load_scene(path)
    assert sc.materials[0].bump is not None and sc.materials[0].twosided
    assert not [w for w in recwarn if issubclass(w.category, SceneWarning)]


# ----------------------------------------------------------------------------- normal maps
def normal_xml(extra="", inner='<bsdf type="diffuse"/>', tex_extra='<boolean name="raw" value="true"/>'):
    return (f'<bsdf type="normalmap"><texture name="normalmap" type="bitmap"><string name="filename" value="h.png"/>'
            f'{tex_extra}</texture>{extra}{inner}</bsdf>')


# one texel: the normal 2c - 1 = (0.6, -0.3, 0.7) (unnormalized) in the frame (s, t, ns)
NORMAL_TEXEL = np.array([[[204, 89, 217]]], np.uint8)
NORMAL = 2 * NORMAL_TEXEL[0, 0].astype(float) / 255 - 1


def test_a_normal_map_tilts_the_normal_by_hand(tmp_path):
    """On the rectangle dp/du = (2, 0, 0) and ns = (0, 0, 1): s = (1, 0, 0), t = ns x s =
    (0, 1, 0), so the texel's normal is n = normalize(2c - 1) in world space as it stands;
    `strength` scales its first two components; `uv_handed` turns t against dp/dv = (0, 2, 0)."""
    for extra, expect in (("", NORMAL),
                          ('<float name="strength" value="0.5"/>', NORMAL * (0.5, 0.5, 1.0)),
                          ('<boolean name="uv_handed" value="true"/>', NORMAL * (1.0, -1.0, 1.0))):
        sub = tmp_path / str(len(extra))
        sub.mkdir()
        n, n0, alpha2, _, _ = shade(device_scene(write_scene(sub, normal_xml(extra), NORMAL_TEXEL)), (0.0, 0.0, 1.0))
        np.testing.assert_allclose(n, expect / np.linalg.norm(expect), atol=2e-5)
        # the bump map's terms apply as they stand: ns in the tilted frame, Estevez's alpha^2
        assert n0[2] == pytest.approx(n[2], abs=2e-6)
        assert alpha2 == pytest.approx(min((1 - n[2] ** 2) / n[2] ** 2 / 8, 1.0), rel=1e-4)


def test_an_invalid_map_normal_is_mirrored_about_ns(tmp_path):
    """wi above ns but below the map's normal: mirrored about ns, (x, y, z) -> (-x, -y, z), as
    Mitsuba 3's normalmap flips it; with flip_invalid_normals off it stays."""
    n_map = NORMAL / np.linalg.norm(NORMAL)
    wi = (-1.0, 0.0, 0.2)
    assert np.dot(wi, n_map) < 0 < wi[2]
    for flip, expect in (("", n_map * (-1, -1, 1)), ('<boolean name="flip_invalid_normals" value="false"/>', n_map)):
        sub = tmp_path / str(len(flip))
        sub.mkdir()
        n, *_ = shade(device_scene(write_scene(sub, normal_xml(flip), NORMAL_TEXEL)), wi)
        np.testing.assert_allclose(n, expect, atol=2e-5)


def test_a_flat_normal_map_changes_nothing(tmp_path):
    """(0.5, 0.5, 1): the normal ns itself, and a diffuse's eval equal to the plain diffuse's."""
    flat = np.array([[[128, 128, 255]]], np.uint8)  # 128/255 is not exactly 1/2: 2c - 1 = 1/255
    wos = [(0.3, 0.2, 1.0), (-0.5, 0.1, 0.4)]
    n, _, _, f, pdf = shade(device_scene(write_scene(tmp_path, normal_xml(), flat)), (0.0, 0.3, 1.0), wos)
    np.testing.assert_allclose(n, (0, 0, 1), atol=6e-3)
    for i, wo in enumerate(wos):
        wo = np.array(wo) / np.linalg.norm(wo)
        np.testing.assert_allclose(f[i], 0.5 / math.pi * np.dot(wo, n), rtol=1e-3)


@pytest.mark.parametrize("bsdf,message", [
    ('<bsdf type="twosided">{}</bsdf>'.format(normal_xml()), "normalmap inside a twosided"),
    (normal_xml(inner=bump_xml()), "nested bumpmap and normalmap"),
    ('<bsdf type="normalmap"><bsdf type="diffuse"/></bsdf>', "exactly one nested BSDF and one texture"),
    ('<bsdf type="normalmap"><texture name="normalmap" type="checkerboard"/><bsdf type="diffuse"/></bsdf>',
     "not a normal map"),
])
def test_bad_normal_maps_are_refused(tmp_path, bsdf, message):
    with pytest.raises(SceneError, match=message):
        restir.load_scene(write_scene(tmp_path, bsdf, NORMAL_TEXEL))


def test_an_srgb_normal_map_is_said(tmp_path):
    """Without raw=true Mitsuba 3 decodes the 8-bit file as sRGB, and so does restir; said."""
    with pytest.warns(SceneWarning, match="read as sRGB-encoded"):
        sc = restir.load_scene(write_scene(tmp_path, normal_xml(tex_extra=""), NORMAL_TEXEL))
    (m,) = sc.materials
    assert m.bump.kind == "normal" and m.bump.scale == 1.0 and not m.bump.uv_handed
