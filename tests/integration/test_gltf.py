"""The glTF 2.0 reader (restir/scene/gltf/): a glTF twin of the Cornell box renders as the same
box built directly (same materials), a point light over a plane and a directional light on a
plane match their closed forms, and the reader's conventions and refusals."""
import io
import math
import warnings

import numpy as np
import pytest

import restir
from restir.scene.builtin import builtin_scene
from restir.scene.errors import SceneError, SceneWarning
from tests.gltf_files import appendix_b, camera_node, write_gltf, yfov_of

pytest.importorskip("pygltflib")


def mr(base, metallic=0.0, roughness=1.0, **extra) -> dict:
    return {"pbr": {"baseColorFactor": [*base, 1.0], "metallicFactor": metallic, "roughnessFactor": roughness}, **extra}


def cornell_twin(tmp_path, size=32):
    """The builtin Cornell box as a glTF file, its diffuse walls as metallic-roughness (metallic 0,
    roughness 1, doubleSided), and the same box as a restir dict with those materials."""
    box = builtin_scene("cornell-box", width=size, height=size, spp=16)
    meshes, materials, keys = [], [], {}
    for name, shape in box.items():
        if not isinstance(shape, dict) or shape.get("type") != "trimesh":
            continue
        refl = shape["bsdf"]["bsdf"]["reflectance"]["value"]
        key = tuple(refl)
        if key not in keys:
            extra = {"doubleSided": True}
            if "emitter" in shape:
                light = np.array(shape["emitter"]["radiance"]["value"], float)
                strength = float(light.max())
                extra.update(emissiveFactor=(light / strength).tolist(),
                             extensions={"KHR_materials_emissive_strength": {"emissiveStrength": strength}})
            keys[key] = len(materials)
            materials.append(mr(refl, **extra))
        meshes.append((shape["vertices"], shape["faces"], keys[key], {}))
        shape["bsdf"] = {"type": "twosided", "bsdf": {"type": "metallic_roughness", "base_color": np.array(refl, float),
                                                      "metallic": 0.0, "roughness": 1.0}}
    sensor = box["sensor"]
    sensor["film"]["rfilter"] = {"type": "box"}  # a glTF file has no pixel filter: restir reads it with a box
    cam = (camera_node(sensor["to_world"]), yfov_of(sensor["fov"], 1.0), 1.0, "main")
    path = write_gltf(tmp_path / "box.glb", meshes, materials, camera=cam,
                      extensions_required=["KHR_materials_emissive_strength"])
    return path, box


def test_the_cornell_box_twin_renders_as_the_box(tmp_path):
    path, box = cornell_twin(tmp_path)
    with warnings.catch_warnings():
        warnings.simplefilter("error", SceneWarning)
        twin = restir.load_scene(path, camera="main")
    direct = restir.load_scene(box)
    assert twin.num_triangles == direct.num_triangles
    assert np.allclose(twin.camera.to_world, direct.camera.to_world, atol=1e-6)
    kw = dict(method="pt", spp=64, frames=4, width=32, height=32)
    a = restir.render(twin, seed=1, **kw)
    b = restir.render(direct, seed=2, **kw)
    # 8 x 8 blocks of 4 x 4 pixels: z of the difference of the block means
    blocks = lambda r: r.image.reshape(8, 4, 8, 4, 3).mean((1, 3))  # noqa: E731
    var = lambda r: (r.sample_var / r.samples).reshape(8, 4, 8, 4, 3).sum((1, 3)) / 256  # noqa: E731
    z = (blocks(a) - blocks(b)) / np.sqrt(var(a) + var(b) + 1e-12)
    # 192 cells at |z| < 4.5: a false failure under 1e-3 (Bonferroni); the smallest detectable
    # difference is about 4.5 standard errors of a block, about 3% of its mean here
    assert np.max(np.abs(z)) < 4.5, np.max(np.abs(z))
    assert abs(a.image.mean() / b.image.mean() - 1) < 0.02


def plane(size=10.0, z=0.0):
    v = np.array([[-size, -size, z], [size, -size, z], [size, size, z], [-size, size, z]], float)
    return v, np.array([[0, 1, 2], [0, 2, 3]])


def top_down_camera(height):
    """A camera node at (0, 0, height) looking down -Z (glTF's own axis), +Y up in the image."""
    m = np.eye(4)
    m[2, 3] = height
    return m


@pytest.mark.parametrize("metallic,roughness", [(0.0, 1.0), (0.0, 0.5), (1.0, 0.7)])
def test_a_point_light_over_a_plane_matches_the_closed_form(tmp_path, metallic, roughness):
    """The camera and a point light at height h above a plane: the pixel at the centre sees
    f(n, n) cos I / h^2, with f the specification's BRDF at normal incidence."""
    h, intensity, base = 2.0, 5.0, np.array([0.6, 0.4, 0.2])
    v, f = plane()
    light = ({"type": "point", "color": [1, 1, 1], "intensity": intensity}, top_down_camera(h))
    path = write_gltf(tmp_path / "p.gltf", [(v, f, 0, {})], [mr(base, metallic, roughness)],
                      camera=(top_down_camera(h), math.radians(10), 1.0, "cam"), lights=[light])
    scene = restir.load_scene(path)
    assert scene.delta_lights[0].kind == "point" and np.allclose(scene.delta_lights[0].intensity, intensity)
    img = restir.render(scene, method="pt", spp=4, width=9, height=9, seed=3).image
    n = np.array([[0.0, 0.0, 1.0]])
    want = appendix_b(base, metallic, max(roughness, 1e-2) ** 2, n, n)[0] * intensity / h ** 2
    np.testing.assert_allclose(img[4, 4], want, rtol=0.02)


def test_a_directional_light_is_irradiance_along_the_nodes_minus_z(tmp_path):
    """The sun at 60 degrees from the normal: a Lambert-like rough non-metal seen from above has
    radiance f(wi = n, wo = sun) E."""
    base = np.array([0.5, 0.5, 0.5])
    v, f = plane()
    tilt = math.radians(60)
    sun = np.eye(4)  # its -Z is the direction the light travels: (sin, 0, -cos)
    sun[:3, 2] = [-math.sin(tilt), 0.0, math.cos(tilt)]
    sun[:3, 0] = [math.cos(tilt), 0.0, math.sin(tilt)]
    light = ({"type": "directional", "color": [1, 1, 1], "intensity": 3.0}, sun)
    path = write_gltf(tmp_path / "s.gltf", [(v, f, 0, {})], [mr(base, 0.0, 1.0)],
                      camera=(top_down_camera(2.0), math.radians(10), 1.0, "cam"), lights=[light])
    scene = restir.load_scene(path)
    assert np.allclose(scene.delta_lights[0].axis, [math.sin(tilt), 0, -math.cos(tilt)], atol=1e-9)
    img = restir.render(scene, method="pt", spp=4, width=9, height=9, seed=3).image
    wi, wo = np.array([[0.0, 0.0, 1.0]]), np.array([[-math.sin(tilt), 0.0, math.cos(tilt)]])
    want = appendix_b(base, 0.0, 1.0, wi, wo)[0] * 3.0
    np.testing.assert_allclose(img[4, 4], want, rtol=0.02)


def test_the_camera_sees_plus_x_on_the_right(tmp_path):
    """glTF's camera looks down -Z with +X to the right: an emitter at +X is on the right."""
    v, f = plane(1.0)
    v[:, 0] += 1.5  # the square spans x in [0.5, 2.5]
    path = write_gltf(tmp_path / "c.gltf", [(v, f, 0, {})],
                      [mr([0, 0, 0], emissiveFactor=[1, 1, 1])], camera=(top_down_camera(3.0), math.radians(90), 1.0, "c"))
    img = restir.render(restir.load_scene(path), method="pt", spp=1, width=16, height=16, seed=1).image.mean(axis=2)
    assert img[8, 12] == pytest.approx(1.0) and img[:, :6].max() == 0.0


def test_textures_alpha_mask_and_transform(tmp_path):
    """A 2 x 1 base-colour texture (left red, right blue, alpha 1 and 0) with alphaMode MASK: the
    blue half is cut out; KHR_texture_transform's offset of half the image swaps the halves."""
    from PIL import Image

    png = io.BytesIO()
    Image.fromarray(np.array([[[255, 0, 0, 255], [0, 0, 255, 0]]], np.uint8), "RGBA").save(png, format="PNG")
    v, f = plane(1.0)
    uvs = np.array([[0, 1], [1, 1], [1, 0], [0, 0]], float)  # glTF: v = 0 at the image's top
    images = []
    for offset in (0.0, 0.5):
        tex = {"index": 0}
        if offset:
            tex["extensions"] = {"KHR_texture_transform": {"offset": [offset, 0.0]}}
        mat = {"pbr": {"baseColorFactor": [1, 1, 1, 1], "metallicFactor": 0.0, "roughnessFactor": 1.0,
                       "baseColorTexture": tex}, "alphaMode": "MASK", "emissiveFactor": [0, 0, 0]}
        light = ({"type": "directional", "color": [1, 1, 1], "intensity": 3.0}, np.eye(4))
        path = write_gltf(tmp_path / f"t{offset}.glb", [(v, f, 0, {"uvs": uvs})], [mat],
                          camera=(top_down_camera(2.0), math.radians(60), 1.0, "c"), lights=[light],
                          images=[png.getvalue()], extensions_required=["KHR_texture_transform"])
        scene = restir.load_scene(path)
        images.append(restir.render(scene, method="pt", spp=1, width=16, height=16, seed=1).image)
    a, b = images
    # left red (the blue is the 4% specular reflection of the white sun), right cut out
    assert a[8, 5, 0] > 10 * a[8, 5, 2] > 0 and a[8, 11].max() == 0.0
    assert b[8, 11, 0] > 10 * b[8, 11, 2] > 0 and b[8, 5].max() == 0.0  # shifted by half


def _png(rgb) -> bytes:
    from PIL import Image

    out = io.BytesIO()
    Image.fromarray(np.array([[rgb]], np.uint8)).save(out, format="PNG")
    return out.getvalue()


def test_a_normal_map_tilts_toward_the_images_top_on_mirrored_uvs_too(tmp_path):
    """A one-texel normal map tilting 30 degrees toward the image's top (green, glTF's +Y), on a
    plane whose image top is +Y in the world, mapped as it stands and mirrored (u reversed): in
    both the normal tilts toward +Y (MikkTSpace's bitangent sign), so under a sun from the +Y side
    both are brighter than the flat plane and equal. With the sign ignored (Mitsuba's frame), the
    mirrored one tilts away and is darker."""
    a = math.radians(30)
    png = _png(np.round((np.array([0.0, math.sin(a), math.cos(a)]) + 1) * 127.5))
    v, f = plane(1.0)
    straight = np.array([[0, 1], [1, 1], [1, 0], [0, 0]], float)  # glTF: v = 0 at the image's top
    mirrored = np.array([[1, 1], [0, 1], [0, 0], [1, 0]], float)
    b = math.radians(50)  # the sun travels along (0, -sin b, -cos b): it shines from the +Y side
    sun = np.eye(4)
    sun[:3, :3] = [[1, 0, 0], [0, math.cos(b), math.sin(b)], [0, -math.sin(b), math.cos(b)]]  # -Z to the sun's path
    light = ({"type": "directional", "color": [1, 1, 1], "intensity": 2.0}, sun)

    def centre(uvs, normal_texture=None, flip=False):
        mat = mr([0.8, 0.8, 0.8])
        if normal_texture is not None:
            mat["normalTexture"] = normal_texture
        path = write_gltf(tmp_path / f"n{len(list(tmp_path.iterdir()))}.glb", [(v, f, 0, {"uvs": uvs})], [mat],
                          camera=(top_down_camera(2.0), math.radians(30), 1.0, "c"), lights=[light],
                          images=[png] if normal_texture else [])
        scene = restir.load_scene(path)
        if normal_texture is not None:
            (m,) = scene.materials
            assert m.bump.kind == "normal" and m.bump.uv_handed and m.bump.scale == normal_texture.get("scale", 1.0)
            m.bump.uv_handed = not flip
        return restir.render(scene, method="pt", spp=1, width=8, height=8, seed=1).image[4, 4].mean()

    flat = centre(straight)
    tilted, tilted_mirrored = centre(straight, {"index": 0}), centre(mirrored, {"index": 0})
    assert tilted > 1.1 * flat
    assert tilted_mirrored == pytest.approx(tilted, rel=1e-4)
    assert centre(mirrored, {"index": 0}, flip=True) < 0.9 * flat
    # scale 0 on x and y: the normal (0, 0, cos a) is the plane's own
    assert centre(straight, {"index": 0, "scale": 0.0}) == pytest.approx(flat, rel=1e-4)


def test_a_files_tangents_give_the_normal_maps_frame(tmp_path):
    """TANGENT (xyz, w) per vertex: the map's +Y (green) is w (n x tangent), glTF's bitangent. On
    the plane of the test above (image top at world +Y, n = +Z), the tangent -X with w = 1, or +X
    with w = -1, puts the map's +Y on world -Y: the tilt toward the image's top now points away
    from the sun, and the plane is darker than flat; +X with w = 1 is the frame derived from the
    uvs."""
    a = math.radians(30)
    png = _png(np.round((np.array([0.0, math.sin(a), math.cos(a)]) + 1) * 127.5))
    v, f = plane(1.0)
    uvs = np.array([[0, 1], [1, 1], [1, 0], [0, 0]], float)
    sun = np.eye(4)
    b = math.radians(50)
    sun[:3, :3] = [[1, 0, 0], [0, math.cos(b), math.sin(b)], [0, -math.sin(b), math.cos(b)]]
    light = ({"type": "directional", "color": [1, 1, 1], "intensity": 2.0}, sun)

    def centre(tangent=None, normal_map=True):
        extras = {"uvs": uvs}
        if tangent is not None:
            extras["tangents"] = np.tile(np.asarray(tangent, float), (4, 1))
        mat = mr([0.8, 0.8, 0.8])
        if normal_map:
            mat["normalTexture"] = {"index": 0}
        path = write_gltf(tmp_path / f"t{len(list(tmp_path.iterdir()))}.glb", [(v, f, 0, extras)], [mat],
                          camera=(top_down_camera(2.0), math.radians(30), 1.0, "c"), lights=[light],
                          images=[png] if normal_map else [])
        scene = restir.load_scene(path)
        assert (scene.tangents is not None) == (tangent is not None and normal_map)
        return restir.render(scene, method="pt", spp=1, width=8, height=8, seed=1).image[4, 4].mean()

    flat, derived = centre(normal_map=False), centre()
    assert derived > 1.1 * flat
    assert centre([1, 0, 0, 1]) == pytest.approx(derived, rel=1e-4)
    assert centre([-1, 0, 0, 1]) < 0.9 * flat
    assert centre([1, 0, 0, -1]) == pytest.approx(centre([-1, 0, 0, 1]), rel=1e-4)
    assert centre([1, 0, 0, 1], normal_map=False) == pytest.approx(flat, rel=1e-6)  # no map: not read


def test_a_double_sided_emissive_material_lights_both_sides(tmp_path):
    v, f = plane(1.0)
    below = np.diag([1.0, -1.0, -1.0, 1.0])  # a camera under the plane, looking up +Z
    below[2, 3] = -2.0
    for double, expect in ((True, 0.5), (False, 0.0)):
        path = write_gltf(tmp_path / f"e{double}.gltf", [(v, f, 0, {})],
                          [mr([0, 0, 0], emissiveFactor=[0.5, 0.5, 0.5], doubleSided=double)],
                          camera=(below, math.radians(40), 1.0, "c"))
        scene = restir.load_scene(path)
        assert (scene.tri_emit_twosided is not None) == double
        img = restir.render(scene, method="pt", spp=1, width=8, height=8, seed=1).image
        np.testing.assert_allclose(img[4, 4], expect, atol=1e-6)


def test_transmission_mixes_a_dielectric_in(tmp_path):
    v, f = plane(1.0)
    mats = [mr([0.9, 0.9, 0.9], 0.0, 0.0, extensions={"KHR_materials_transmission": {"transmissionFactor": 0.25},
                                                       "KHR_materials_ior": {"ior": 1.33}})]
    path = write_gltf(tmp_path / "g.gltf", [(v, f, 0, {})], mats, camera=(top_down_camera(2.0), 1.0, 1.0, "c"),
                      extensions_required=["KHR_materials_transmission", "KHR_materials_ior"])
    scene = restir.load_scene(path)
    kinds = [m.kind for m in scene.materials]
    assert kinds == ["metallic_roughness", "dielectric", "mixture"]
    assert math.isclose(scene.materials[2].mix_amount, 0.25) and math.isclose(scene.materials[1].ior, 1.33)


def test_refusals_and_warnings(tmp_path):
    v, f = plane(1.0)
    path = write_gltf(tmp_path / "r.gltf", [(v, f, 0, {})], [mr([1, 1, 1])], extensions_required=["KHR_draco_mesh_compression"])
    with pytest.raises(SceneError, match="requires the extension 'KHR_draco_mesh_compression'"):
        restir.load_scene(path)
    path = write_gltf(tmp_path / "n.gltf", [(v, f, None, {})], [])
    with pytest.warns(SceneWarning, match="no camera: the view is a default framing"):
        scene = restir.load_scene(path)
    assert scene.materials[0].kind == "metallic_roughness" and scene.materials[0].metallic == 1.0
    with pytest.raises(SceneError, match="no camera node named 'x'"):
        restir.load_scene(write_gltf(tmp_path / "m.gltf", [(v, f, 0, {})], [mr([1, 1, 1])],
                                     camera=(np.eye(4), 1.0, 1.0, "cam")), camera="x")
    with pytest.raises(SceneError, match="unknown parameter"):
        restir.load_scene(path, spp=4)


# ------------------------------------------------------------------ animations
def _box(size=0.2):
    """A small cube's 8 vertices and 12 triangles about the origin."""
    v = np.array([[x, y, z] for x in (-size, size) for y in (-size, size) for z in (-size, size)], float)
    f = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                  [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])
    return v, f


def _z_rotation(deg):
    h = math.radians(deg) / 2
    return [0.0, 0.0, math.sin(h), math.cos(h)]


def test_node_animations_move_meshes_their_children_and_lights(tmp_path):
    """Channels of one animation at fps 4 (1 s = 4 frames): the parent box translates (linear), its
    child turns with it; another box steps; a third follows a cubic spline whose tangents are per
    second; a point light's node translates."""
    from restir.scene.animation import posed_scene

    v, f = _box()
    ident = ([0, 0, 0], [0, 0, 0, 1], [1, 1, 1])
    meshes = [(v, f, 0, {"trs": ident, "name": "parent"}),
              (v, f, 0, {"trs": ([1.0, 0, 0], [0, 0, 0, 1], [1, 1, 1]), "parent": 0, "name": "child"}),
              (v, f, 0, {"trs": ([0, 2.0, 0], [0, 0, 0, 1], [1, 1, 1])}),
              (v, f, 0, {"trs": ([0, -2.0, 0], [0, 0, 0, 1], [1, 1, 1])})]
    light = ({"type": "point", "color": [1, 1, 1], "intensity": 2.0}, ([0, 0, 3.0], [0, 0, 0, 1], [1, 1, 1]))
    cubic = np.array([[[0, 0, 0], [0, 0, 0], [4.0, 0, 0]],      # in, value, out (per second)
                      [[0, 0, 0], [1.0, 0, 0], [0, 0, 0]]])
    anims = [(0, "translation", [0, 1], [[0, 0, 0], [0, 0, 1.0]], "LINEAR"),
             (0, "rotation", [0, 1], [[0, 0, 0, 1], _z_rotation(90)], "LINEAR"),
             (2, "translation", [0, 0.5], [[0, 2.0, 0], [0, 2.0, 5.0]], "STEP"),
             (3, "translation", [0, 1], cubic + np.array([0, -2.0, 0]) * np.array([[[0], [1], [0]]]), "CUBICSPLINE"),
             (5, "translation", [0, 1], [[0, 0, 3.0], [0.5, 0, 3.0]], "LINEAR")]  # node 5: the light (4 is the camera)
    path = write_gltf(tmp_path / "a.gltf", meshes, [mr([0.5, 0.5, 0.5])], lights=[light],
                      camera=(top_down_camera(8.0), math.radians(40), 1.0, "cam"), animations=anims)
    scene = restir.load_scene(path, fps=4)
    assert scene.animation is not None and scene.animation.frames == 5
    rest = scene.positions
    p = posed_scene(scene, 2).positions  # t = 0.5 s
    centre = lambda pos, name: pos[slice(*scene.objects[name])].reshape(-1, 3).mean(0)  # noqa: E731
    np.testing.assert_allclose(centre(p, "shape_0"), [0, 0, 0.5], atol=1e-5)
    # the child at (1, 0, 0) under the parent turned 45 degrees about z and lifted 0.5
    np.testing.assert_allclose(centre(p, "shape_1"), [math.cos(math.pi / 4), math.sin(math.pi / 4), 0.5], atol=1e-5)
    np.testing.assert_allclose(centre(posed_scene(scene, 1).positions, "shape_2"), centre(rest, "shape_2"), atol=1e-6)
    np.testing.assert_allclose(centre(p, "shape_2"), [0, 2.0, 5.0], atol=1e-5)
    # Hermite at s = 1/2 over 1 s: v0/2 + b0/8 + v1/2 - a1/8, b0 = 4 per second
    np.testing.assert_allclose(centre(p, "shape_3"), [0.5 * 0 + 4.0 / 8 + 0.5 * 1.0, -2.0, 0], atol=1e-5)
    np.testing.assert_allclose(posed_scene(scene, 2).delta_lights[0].position, [0.25, 0, 3.0], atol=1e-6)
    r = restir.render(scene, method="restir-di", spp=1, frames=5, width=16, height=16, keep_frames=True)
    assert r.frame_images.shape == (5, 16, 16, 3) and np.all(np.isfinite(r.frame_images))


def test_animation_refusals_and_warnings(tmp_path):
    v, f = _box()
    m = np.eye(4)
    path = write_gltf(tmp_path / "m.gltf", [(v, f, 0, {"matrix": m})], [mr([0.5, 0.5, 0.5])],
                      animations=[(0, "translation", [0, 1], [[0, 0, 0], [1, 0, 0]], "LINEAR")])
    with pytest.raises(SceneError, match="has a matrix"):
        restir.load_scene(path)
    path = write_gltf(tmp_path / "c.gltf", [(v, f, 0, {"trs": ([0, 0, 0], [0, 0, 0, 1], [1, 1, 1])})],
                      [mr([0.5, 0.5, 0.5])], camera=(([0, 0, 3.0], [0, 0, 0, 1], [1, 1, 1]), math.radians(40), 1.0, "cam"),
                      animations=[(1, "translation", [0, 1], [[0, 0, 3.0], [1, 0, 3.0]], "LINEAR")])
    with pytest.warns(SceneWarning, match="camera's animation is not played"):
        scene = restir.load_scene(path)
    assert scene.animation is None  # only the camera moved: nothing that renders
    with pytest.raises(SceneError, match="fps"):
        restir.load_scene(path, fps="fast")
