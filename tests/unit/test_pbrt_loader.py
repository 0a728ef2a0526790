"""The pbrt-v4 reader (restir/scene/pbrt/): tokens, parameters, graphics state, and the
conventions where pbrt-v4 and Mitsuba differ (a left-handed camera, image rows looked up at
1 - v, maxdepth counting bounces, the film's imaging ratio, a spot's smoothstep), each checked
on what the loader builds or renders."""
import math
import warnings

import numpy as np
import pytest

import restir
from restir.scene.errors import SceneError, SceneWarning
from restir.scene.pbrt import spectra
from restir.scene.pbrt.params import read_params
from restir.scene.pbrt.reader import load_pbrt
from restir.scene.pbrt.tokens import Tokenizer
from restir.scene.transforms import rotate

CAMERA = 'LookAt 0 0 0  0 0 1  0 1 0\nCamera "perspective" "float fov" [ 40 ]\n'
FILM = 'Film "rgb" "integer xresolution" [ 32 ] "integer yresolution" [ 32 ]\nPixelFilter "box"\n'
QUAD = ('Shape "trianglemesh" "point3 P" [ {x0} {y0} {z}  {x1} {y0} {z}  {x1} {y1} {z}  {x0} {y1} {z} ] '
        '"integer indices" [ 0 1 2 0 2 3 ] "point2 uv" [ 0 0 1 0 1 1 0 1 ] {extra}\n')


def write(tmp_path, text: str, name: str = "scene.pbrt") -> str:
    path = tmp_path / name
    path.write_text(text)
    return str(path)


def quad(x0, x1, y0, y1, z, extra=""):
    return QUAD.format(x0=x0, x1=x1, y0=y0, y1=y1, z=z, extra=extra)


def render(path, spp=16, **kw):
    scene = restir.load_scene(path)
    return restir.render(scene, method="pt", spp=spp, seed=1, **kw).image


# ----------------------------------------------------------------------------- tokens and parameters
def test_tokens_strings_comments_and_lines(tmp_path):
    t = Tokenizer(write(tmp_path, 'Shape # a comment "not a string"\n  "string a\\"b" [ 1\n 2 ]\nWorldBegin'))
    out = []
    while (tok := t.next()) is not None:
        out.append((tok.text, tok.line, tok.quoted))
    assert out == [("Shape", 1, False), ('string a"b', 2, True), ("[", 2, False), ("1", 2, False), ("2", 3, False),
                   ("]", 3, False), ("WorldBegin", 4, False)]


def test_parameters_are_typed_and_bracketed_numbers_read_at_once(tmp_path):
    t = Tokenizer(write(tmp_path, '"float fov" 45 "point3 P" [ 0 0 0\n 1 0 0 ] "bool on" "true" "string s" [ "x" ]\n'
                                  'Next'))
    ps = read_params(t, "Camera", "f:1")
    assert ps.float("fov") == 45.0 and ps.bool("on") is True and ps.string("s") == "x"
    assert ps.array("P", ("point3",), 3).shape == (2, 3)
    assert t.next().text == "Next" and t.line == 3
    with pytest.raises(SceneError, match="'fov' must be an integer, not 'float'"):
        ps.int("fov")


def test_a_parameter_never_read_is_a_warning_with_its_line(tmp_path):
    path = write(tmp_path, CAMERA + "WorldBegin\n" + 'LightSource "point" "rgb I" [1 1 1]\n  "float fvo" [ 2 ]\n'
                 + quad(-1, 1, -1, 1, 5))
    with pytest.warns(SceneWarning, match=r"scene.pbrt:5: LightSource \"point\": unused parameter 'float fvo'"):
        load_pbrt(path)


# ----------------------------------------------------------------------------- transforms and state
def test_transform_directives_compose_as_pbrt(tmp_path):
    path = write(tmp_path, CAMERA + "WorldBegin\nAttributeBegin\n"
                 "Transform [ 1 0 0 0  0 1 0 0  0 0 1 0  2.3 0 0 1 ]\nRotate 30 0 0 1\nScale 2 2 2\n"
                 + quad(0, 1, 0, 1, 0) + "AttributeEnd\n" + quad(0, 1, 0, 1, 7))
    tree = load_pbrt(path)
    p0 = tree["shape_0"]["load"]().positions.reshape(-1, 3)
    p1 = tree["shape_1"]["load"]().positions.reshape(-1, 3)
    m = np.eye(4)
    m[0, 3] = 2.3
    m = m @ rotate([0, 0, 1], 30) @ np.diag([2.0, 2.0, 2.0, 1.0])
    corner = m[:3, :3] @ np.array([1.0, 1.0, 0.0]) + m[:3, 3]
    assert np.min(np.linalg.norm(p0 - corner, axis=1)) < 1e-12
    assert np.allclose(p1[:, 2], 7.0)  # AttributeEnd restored the identity


def test_object_instances_copy_the_object_under_each_transform(tmp_path):
    path = write(tmp_path, CAMERA + "WorldBegin\nObjectBegin \"q\"\n" + quad(0, 1, 0, 1, 0) + "ObjectEnd\n"
                 "AttributeBegin\nTranslate 0 0 5\nObjectInstance \"q\"\nAttributeEnd\n"
                 "AttributeBegin\nTranslate 0 0 9\nObjectInstance \"q\"\nAttributeEnd\n")
    tree = load_pbrt(path)
    zs = [tree[f"shape_{i}"]["load"]().positions[..., 2].mean() for i in range(2)]
    assert np.allclose(zs, [5.0, 9.0]) and "shape_2" not in tree


def test_maxdepth_counts_bounces_and_the_imaging_ratio_scales_emitters(tmp_path):
    base = CAMERA + 'Film "rgb" "float iso" [ 200 ]\nIntegrator "path" "integer maxdepth" [ 3 ]\nWorldBegin\n'
    scene = restir.load_scene(write(tmp_path, base + 'AreaLightSource "diffuse" "rgb L" [ 1 2 3 ]\n'
                                    + quad(-1, 1, -1, 1, 5, '"normal N" [0 0 -1 0 0 -1 0 0 -1 0 0 -1]')))
    assert scene.max_depth == 4
    assert np.allclose(scene.tri_emission.max(axis=0), [2.0, 4.0, 6.0])
    no_integrator = restir.load_scene(write(tmp_path, CAMERA + "WorldBegin\n" + quad(-1, 1, -1, 1, 5), "b.pbrt"))
    assert no_integrator.max_depth == 6  # pbrt-v4's default maxdepth 5


# ----------------------------------------------------------------------------- conventions, rendered
def test_the_camera_is_left_handed_as_pbrt(tmp_path):
    """Looking down +z with +y up, pbrt-v4's +x is on the image's right (a left-handed frame); a
    Mitsuba lookat with the same vectors puts it on the left."""
    path = write(tmp_path, CAMERA + FILM + "WorldBegin\n" + 'AreaLightSource "diffuse" "rgb L" [ 1 1 1 ]\n'
                 + quad(0.2, 2, -1, 1, 5, '"normal N" [0 0 -1 0 0 -1 0 0 -1 0 0 -1]'))
    img = render(path, spp=4).mean(axis=2)
    assert img[:, 20:].mean() > 0.5 and img[:, :12].mean() == 0.0


def test_an_area_light_emits_to_the_side_its_normals_face(tmp_path):
    toward = '"normal N" [0 0 -1 0 0 -1 0 0 -1 0 0 -1]'
    away = '"normal N" [0 0 1 0 0 1 0 0 1 0 0 1]'
    imgs = []
    for name, n in (("toward.pbrt", toward), ("away.pbrt", away)):
        path = write(tmp_path, CAMERA + FILM + "WorldBegin\n" + 'AreaLightSource "diffuse" "rgb L" [ 1 1 1 ]\n'
                     'Material "diffuse" "rgb reflectance" [ 0 0 0 ]\n' + quad(-3, 3, -3, 3, 5, n), name)
        imgs.append(render(path, spp=1))
    assert np.allclose(imgs[0][16, 16], 1.0) and np.allclose(imgs[1], 0.0)
    # "bool twosided": both sides
    path = write(tmp_path, CAMERA + FILM + "WorldBegin\n" + 'AreaLightSource "diffuse" "rgb L" [ 1 1 1 ] '
                 '"bool twosided" true\nMaterial "diffuse" "rgb reflectance" [ 0 0 0 ]\n' + quad(-3, 3, -3, 3, 5, away),
                 "twosided.pbrt")
    assert np.allclose(render(path, spp=1)[16, 16], 1.0)


def test_a_two_sided_area_lights_power_is_spread_over_both_sides(tmp_path):
    """pbrt-v4: L = power / (2 pi A) for a two-sided emitter, power / (pi A) for a one-sided one."""
    for twosided, sides in (("true", 2), ("false", 1)):
        path = write(tmp_path, CAMERA + "WorldBegin\n" + f'AreaLightSource "diffuse" "float power" 10 '
                     f'"bool twosided" {twosided}\n' + quad(-1, 1, -2, 2, 5), f"{twosided}.pbrt")
        scene = restir.load_scene(path)
        assert np.allclose(scene.tri_emission, 10 / (sides * math.pi * 8.0), rtol=1e-5)
        assert (scene.tri_emit_twosided is not None) == (sides == 2)
        assert scene.light_power().sum() == pytest.approx(10 / math.pi, rel=1e-5)  # power / pi either way


def test_a_normal_map_is_read_linear_and_wins_over_displacement(tmp_path):
    """"string normalmap": the image read linear, repeated and bilinear (pbrt-v4's Image::Read
    with a linear encoding), as restir's normalmap; with a displacement as well, pbrt-v4 applies
    only the normal map, and restir says so."""
    from PIL import Image

    Image.fromarray(np.array([[[200, 100, 230]]], np.uint8)).save(tmp_path / "n.png")
    Image.fromarray(np.full((2, 2), 90, np.uint8)).save(tmp_path / "h.png")
    material = 'Material "diffuse" "string normalmap" "n.png"'
    disp = ' "texture displacement" "h"'
    for extra, warned in (("", []), (disp, ["'displacement' is not applied"])):
        path = write(tmp_path, CAMERA + "WorldBegin\n" + 'Texture "h" "float" "imagemap" "string filename" "h.png"\n'
                     + material + extra + "\n" + quad(-1, 1, -1, 1, 5), f"n{len(extra)}.pbrt")
        with pytest.warns(SceneWarning) as rec:
            scene = restir.load_scene(path)
        said = " ".join(str(w.message) for w in rec)
        assert "rendered as Mitsuba 3's normalmap and bumpmap" in said
        assert all(w in said for w in warned)
        (m,) = scene.materials
        assert m.bump.kind == "normal" and m.twosided and m.bump.scale == 1.0 and not m.bump.uv_handed
        tex = scene.textures[m.bump.texture]
        assert (tex.wrap, tex.filter) == ("repeat", "bilinear")
        np.testing.assert_allclose(tex.image[0, 0], np.array([200, 100, 230]) / 255, rtol=1e-6)


def test_an_image_texture_is_upright_where_uv_v_grows_upward(tmp_path):
    """pbrt-v4 looks an image up at (u, 1 - v) with its first row at the top: on a quad whose v
    grows upward, the image's top row is at the top."""
    from PIL import Image

    Image.fromarray(np.array([[[255, 0, 0]], [[0, 255, 0]]], np.uint8)).save(tmp_path / "tex.png")
    path = write(tmp_path, CAMERA + FILM + "WorldBegin\n" + 'LightSource "distant" "point3 from" [0 0 0] '
                 '"point3 to" [0 0 1] "rgb L" [ 3 3 3 ]\n'
                 'Texture "t" "spectrum" "imagemap" "string filename" "tex.png" "string filter" "point"\n'
                 'Material "diffuse" "texture reflectance" "t"\n' + quad(-3, 3, -3, 3, 5))
    img = render(path, spp=1)
    top, bottom = img[4], img[27]  # image row 0 is the top
    assert top[:, 0].mean() > 0.5 and top[:, 1].mean() == 0.0
    assert bottom[:, 1].mean() > 0.5 and bottom[:, 0].mean() == 0.0


def test_a_checkerboard_has_unit_checks_starting_with_tex1(tmp_path):
    path = write(tmp_path, CAMERA + FILM + "WorldBegin\n" + 'LightSource "distant" "point3 from" [0 0 0] '
                 '"point3 to" [0 0 1] "rgb L" [ 1 1 1 ]\n'
                 'Texture "c" "spectrum" "checkerboard" "float uscale" 2 "float vscale" 2 '
                 '"rgb tex1" [ 1 0 0 ] "rgb tex2" [ 0 0 1 ]\n'
                 'Material "diffuse" "texture reflectance" "c"\n' + quad(-3, 3, -3, 3, 5))
    img = render(path, spp=1)
    # (s, t) in [0, 2)^2; tex1 where floor(s) + floor(t) is even: s < 1 and t < 1 is the quad's
    # bottom-left in world, which the left-handed camera puts at the image's bottom-left
    assert img[27, 4, 0] > 0.1 and img[27, 4, 2] == 0.0
    assert img[27, 27, 2] > 0.1 and img[27, 27, 0] == 0.0
    assert img[4, 27, 0] > 0.1 and img[4, 4, 2] > 0.1


# ----------------------------------------------------------------------------- lights and spectra
def test_lights_follow_pbrt_v4s_units(tmp_path):
    path = write(tmp_path, CAMERA + "WorldBegin\n"
                 'LightSource "point" "point3 from" [ 1 2 3 ] "rgb I" [ 1 1 1 ] "float power" [ 100 ]\n'
                 'LightSource "spot" "point3 from" [ 0 0 0 ] "point3 to" [ 0 0 -1 ] "float coneangle" 40 '
                 '"float conedeltaangle" 10 "blackbody I" 6500 "float scale" 2\n'
                 'LightSource "distant" "point3 from" [ 0 1 0 ] "point3 to" [ 0 0 0 ] "rgb L" [ 1 1 1 ] '
                 '"float illuminance" 5\n' + quad(-1, 1, -1, 1, 5))
    d = restir.load_scene(path).delta_lights
    assert d[0].kind == "point" and np.allclose(d[0].position, [1, 2, 3]) and np.allclose(d[0].intensity, 100 / (4 * math.pi))
    assert d[1].kind == "spot" and d[1].falloff == "smoothstep" and np.allclose(d[1].axis, [0, 0, -1])
    assert math.isclose(math.degrees(d[1].inner), 30) and math.isclose(math.degrees(d[1].outer), 40)
    assert np.allclose(d[1].intensity, 2 * spectra.blackbody_rgb(6500.0))
    assert d[2].kind == "directional" and np.allclose(d[2].axis, [0, -1, 0]) and np.allclose(d[2].intensity, 5)


def test_spectra_become_rgb_at_unit_luminance():
    lum = np.array([0.2126, 0.7152, 0.0722])
    for t in (2000.0, 5500.0, 10000.0):
        assert math.isclose(float(spectra.blackbody_rgb(t) @ lum), 1.0, rel_tol=2e-3)
    warm, cool = spectra.blackbody_rgb(3000.0), spectra.blackbody_rgb(10000.0)
    assert warm[0] > warm[2] and cool[2] > cool[0]
    assert np.allclose(spectra.emission(("named", "stdillum-D65"), "x"), 1.0, atol=1e-4)
    eta, k = spectra.conductor(("named", "metal-Au-eta"), ("named", "metal-Au-k"), "x", "x")
    r0 = ((eta - 1) ** 2 + k ** 2) / ((eta + 1) ** 2 + k ** 2)
    assert r0[0] > r0[1] > r0[2]  # gold: yellow head-on
    with pytest.raises(SceneError, match="unknown conductor spectrum 'metal-Xx-eta'"):
        spectra.conductor(("named", "metal-Xx-eta"), ("named", "metal-Au-k"), "x", "x")


def test_materials_map_onto_restirs(tmp_path):
    path = write(tmp_path, CAMERA + "WorldBegin\n"
                 'MakeNamedMaterial "g" "string type" "conductor" "spectrum eta" "metal-Au-eta" '
                 '"spectrum k" "metal-Au-k" "float roughness" 0.04\n'
                 'MakeNamedMaterial "glass" "string type" "dielectric" "float eta" 1.33\n'
                 'MakeNamedMaterial "c" "string type" "coateddiffuse" "float roughness" 0.01 '
                 '"rgb reflectance" [ 0.2 0.3 0.4 ]\n'
                 'NamedMaterial "g"\n' + quad(-1, 1, -1, 1, 5) + 'NamedMaterial "glass"\n' + quad(-1, 1, -1, 1, 6)
                 + 'NamedMaterial "c"\n' + quad(-1, 1, -1, 1, 7) + quad(-1, 1, -1, 1, 8))
    with pytest.warns(SceneWarning, match="coateddiffuse .* rendered as a rough plastic"):
        scene = restir.load_scene(path)
    kinds = [m.kind for m in scene.materials]
    assert kinds == ["roughconductor", "dielectric", "roughplastic"]  # the two coated quads share one
    g, glass, c = scene.materials
    assert g.twosided and g.distribution == "ggx" and math.isclose(g.alpha_u, 0.2)
    assert not glass.twosided and math.isclose(glass.ior, 1.33)
    assert c.twosided and math.isclose(c.alpha_u, 0.1) and np.allclose(c.reflectance, [0.2, 0.3, 0.4])


@pytest.mark.parametrize("text,message", [
    ('Material "mix" "string materials" [ "a" "b" ]\n', "unknown named material 'a'"),
    ('Material "diffuse" "texture reflectance" "nope"\n', "unknown texture 'nope'"),
    ('NamedMaterial "nope"\n', "unknown named material 'nope'"),
    ('LightSource "goniometric"\n', "LightSource 'goniometric' is not supported"),
    ('LightSource "infinite" "string filename" "sky.exr"\n', "infinite: environment map 'sky.exr' not found"),
    ('ActiveTransform EndTime\nTranslate 1 0 0\nActiveTransform All\n', "an animated transform"),
    ('Attribute "camera" "float fov" 30\n', "Attribute: unknown target 'camera'"),
])
def test_what_is_not_supported_is_refused_naming_it(tmp_path, text, message):
    path = write(tmp_path, CAMERA + "WorldBegin\n" + text + quad(-1, 1, -1, 1, 5))
    with pytest.raises(SceneError, match=message):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", SceneWarning)
            restir.load_scene(path)


def test_media_are_named_in_a_warning_and_interfaces_left_out(tmp_path):
    path = write(tmp_path, CAMERA + "WorldBegin\n"
                 'MakeNamedMedium "fog" "string type" "homogeneous"\nMediumInterface "fog" ""\n'
                 'Material "interface"\n' + quad(-1, 1, -1, 1, 4) + 'Material "diffuse"\n' + quad(-1, 1, -1, 1, 5))
    with pytest.warns(SceneWarning, match="participating medium 'fog' is not rendered"):
        scene = restir.load_scene(path)
    assert scene.num_triangles == 2  # the interface quad is not a surface


# ----------------------------------------------------------------------------- mix and textured roughness
SUN = 'LightSource "distant" "point3 from" [0 0 0] "point3 to" [0 0 1] "rgb L" [ 1 1 1 ]\n'
RED_BLUE = ('MakeNamedMaterial "red" "string type" "diffuse" "rgb reflectance" [ 0.8 0 0 ]\n'
            'MakeNamedMaterial "blue" "string type" "diffuse" "rgb reflectance" [ 0 0 0.8 ]\n')


def test_mix_takes_the_second_material_with_probability_amount(tmp_path):
    """pbrt-v4's mix picks one material per surface point by a hash; over a pixel's points the
    image is the blend."""
    path = write(tmp_path, CAMERA + FILM + "WorldBegin\n" + SUN + RED_BLUE
                 + 'MakeNamedMaterial "m" "string type" "mix" "string materials" [ "red" "blue" ] "float amount" 0.25\n'
                 'NamedMaterial "m"\n' + quad(-3, 3, -3, 3, 5))
    img = render(path, spp=64).reshape(-1, 3).mean(axis=0)
    assert np.allclose(img[[0, 2]] / (0.8 / math.pi), [0.75, 0.25], atol=0.01), img
    assert img[1] == 0.0


def test_mix_by_a_texture_chooses_where_it_says(tmp_path):
    np.save(tmp_path / "amount.npy", np.repeat(np.array([[[0.0], [1.0]]], np.float32), 3, axis=2))  # left 0, right 1
    path = write(tmp_path, CAMERA + FILM + "WorldBegin\n" + SUN + RED_BLUE
                 + 'Texture "a" "float" "imagemap" "string filename" "amount.npy" "string filter" "point"\n'
                 'MakeNamedMaterial "m" "string type" "mix" "string materials" [ "red" "blue" ] "texture amount" "a"\n'
                 'NamedMaterial "m"\n' + quad(-3, 3, -3, 3, 5))
    img = render(path, spp=1)
    # u grows with world x, which the left-handed camera shows to the right
    assert img[16, 3, 0] > 0.1 and img[16, 3, 2] == 0.0 and img[16, 28, 2] > 0.1 and img[16, 28, 0] == 0.0


def test_a_textured_roughness_renders_as_the_same_constant(tmp_path):
    np.save(tmp_path / "r.npy", np.full((2, 2, 3), 0.09, np.float32))
    lit = (CAMERA + FILM + "WorldBegin\n" + 'LightSource "point" "point3 from" [ 0 0 0 ] "rgb I" [ 10 10 10 ]\n'
           'Texture "r" "float" "imagemap" "string filename" "r.npy" "string encoding" "linear"\n')
    common = '"string type" "conductor" "rgb eta" [ 0.2 0.9 1.1 ] "rgb k" [ 3 2.5 2 ]'
    images = []
    for name, rough in (("const.pbrt", '"float roughness" 0.09'), ("tex.pbrt", '"texture roughness" "r"')):
        path = write(tmp_path, lit + f'MakeNamedMaterial "c" {common} {rough}\nNamedMaterial "c"\n'
                     + quad(-3, 3, -3, 3, 5), name)
        scene = restir.load_scene(path)
        images.append(restir.render(scene, method="pt", spp=4, seed=2).image)
    assert images[0].max() > 0.01
    assert np.allclose(images[0], images[1], rtol=1e-5, atol=1e-7)


# ----------------------------------------------------------------------------- diffusetransmission, image lights
def test_diffusetransmission_maps_with_its_scale(tmp_path):
    path = write(tmp_path, CAMERA + "WorldBegin\n" + SUN
                 + 'Material "diffusetransmission" "rgb reflectance" [ 0.2 0.3 0.4 ] "rgb transmittance" [ 0.5 0.4 0.3 ] '
                 '"float scale" 0.5\n' + quad(-1, 1, -1, 1, 5))
    m = restir.load_scene(path).materials[0]
    assert m.kind == "diffuse_transmission" and m.twosided
    assert np.allclose(m.reflectance, [0.1, 0.15, 0.2]) and np.allclose(m.specular_transmittance, [0.25, 0.2, 0.15])


def test_the_equal_area_map_is_equal_area_and_centred_on_plus_z():
    from restir.scene.pbrt.lights import equal_area_sphere_to_square

    uv = equal_area_sphere_to_square(np.array([[0.0, 0.0, 1.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0]]))
    assert np.allclose(uv[0], [0.5, 0.5]) and np.allclose(uv[1], [1.0, 1.0]) and np.allclose(uv[2], [1.0, 0.5])
    rng = np.random.default_rng(1)
    d = rng.normal(size=(400_000, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    counts = np.histogram2d(*equal_area_sphere_to_square(d).T, bins=8, range=[[0, 1], [0, 1]])[0]
    from scipy import stats

    assert stats.chisquare(counts.reshape(-1)).pvalue > 1e-3  # uniform directions land uniformly


def test_an_image_infinite_light_shines_from_its_maps_centre_along_the_lights_plus_z(tmp_path):
    """A texel at the map's centre is the light-space direction +z; the light's transform turns it
    (here +z to +x), and restir's latitude-longitude map holds it in that direction."""
    img = np.full((32, 32, 3), 0.1, np.float32)
    img[15:17, 15:17] = 50.0
    np.save(tmp_path / "sky.npy", img)
    path = write(tmp_path, CAMERA + "WorldBegin\nAttributeBegin\nRotate 90 0 1 0\n"
                 'LightSource "infinite" "string filename" "sky.npy" "float scale" 2\nAttributeEnd\n'
                 + quad(-1, 1, -1, 1, 5))
    with pytest.warns(SceneWarning, match="resampled to a latitude-longitude map"):
        scene = restir.load_scene(path)
    assert scene.env_kind == "envmap" and scene.env_image.shape == (64, 128, 3) and np.allclose(scene.env_radiance, 2)
    rows, cols = np.nonzero(scene.env_image[..., 0] > 10)
    theta, phi = math.pi * (rows + 0.5) / 64, 2 * math.pi * (cols + 0.5) / 128
    local = np.stack([np.sin(theta) * np.sin(phi), np.cos(theta), -np.sin(theta) * np.cos(phi)], -1)
    world = scene.env_to_world @ local.mean(axis=0)
    assert np.dot(world / np.linalg.norm(world), [1.0, 0.0, 0.0]) > 0.999, world
    # the map's mean over the sphere (latitude rows weighted by their solid angle) is the source's mean
    w = np.sin(math.pi * (np.arange(64) + 0.5) / 64)[:, None]
    assert abs((scene.env_image[..., 0] * w).sum() / (w.sum() * 128) / img[..., 0].mean() - 1) < 0.05


def test_attribute_sets_defaults_within_its_block(tmp_path):
    path = write(tmp_path, CAMERA + "WorldBegin\nAttributeBegin\n"
                 'Attribute "light" "rgb L" [ 2 2 2 ] "float scale" 3\n'
                 'AreaLightSource "diffuse"\n' + quad(-1, 1, -1, 1, 5, '"normal N" [0 0 -1 0 0 -1 0 0 -1 0 0 -1]')
                 + 'AreaLightSource "diffuse" "float scale" 1\n' + quad(-1, 1, -1, 1, 6, '"normal N" [0 0 -1 0 0 -1 0 0 -1 0 0 -1]')
                 + "AttributeEnd\n" + 'AreaLightSource "diffuse"\n' + quad(-1, 1, -1, 1, 7, '"normal N" [0 0 -1 0 0 -1 0 0 -1 0 0 -1]'))
    scene = restir.load_scene(path)
    per_quad = scene.tri_emission[::2, 0]
    assert np.allclose(per_quad, [6.0, 2.0, 1.0])  # defaults, one overridden, and none after the block
