"""Scene-loader semantics that decide an image without any sampling: defaults Mitsuba 3 applies
when the file leaves something out. Deterministic (each value is Mitsuba 3.9.1's, read with its
own loader when the test was written)."""
import numpy as np

import restir
from tests.scenes import V05, V3


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


# ----------------------------------------------------------------------------- Mitsuba 0.5 / 0.6 files
# The names Mitsuba 3's upgrade produces (src/core/parser.cpp camel_to_underscore_case, b45b0a9)
CAMEL = {"toWorld": "to_world", "lookAt": "look_at", "maxDepth": "max_depth", "rrDepth": "rr_depth",
         "sampleCount": "sample_count", "fovAxis": "fov_axis", "intIOR": "int_ior", "extIOR": "ext_ior",
         "specularReflectance": "specular_reflectance", "highQualityEdges": "high_quality_edges",
         "sRGB": "s_rgb", "toWorld2": "to_world2", "uvscale": "uvscale", "uoffset": "uoffset",
         "IORValue": "IORValue", "uv2Scale": "uv2Scale", "XYZ": "XYZ", "aBcD": "a_bc_d"}


def test_camel_to_snake_as_mitsuba():
    from restir.scene.upgrade import camel_to_snake

    assert {k: camel_to_snake(k) for k in CAMEL} == CAMEL


def _load_text(tmp_path, name, text):
    (tmp_path / name).write_text(text)
    return restir.load_scene(str(tmp_path / name))


def test_v05_file_loads_as_its_v3_form(tmp_path, recwarn):
    old, new = _load_text(tmp_path, "old.xml", V05), _load_text(tmp_path, "new.xml", V3)
    assert not [w for w in recwarn if "unused" in str(w.message)], [str(w.message) for w in recwarn]
    for f in ("positions", "normals", "uvs", "tri_smooth", "tri_material", "tri_emission"):
        np.testing.assert_array_equal(getattr(old, f), getattr(new, f), err_msg=f)
    assert (old.max_depth, old.rr_depth, old.spp) == (new.max_depth, new.rr_depth, new.spp) == (7, 3, 9)
    np.testing.assert_array_equal(old.camera.to_world, new.camera.to_world)
    assert old.camera.fov_axis == "y"
    assert [vars(m).keys() for m in old.materials] == [vars(m).keys() for m in new.materials]
    for a, b in zip(old.materials, new.materials):
        for k, v in vars(a).items():
            np.testing.assert_array_equal(v, getattr(b, k), err_msg=k)
    assert len(old.textures) == len(new.textures) == 1
    np.testing.assert_array_equal(old.textures[0].to_uv, new.textures[0].to_uv)
    np.testing.assert_allclose(old.textures[0].to_uv, [[4, 0, 0], [0, 1, 0.25], [0, 0, 1]])
    np.testing.assert_allclose(old.materials[1].reflectance, [0.2, 0.3, 0.4])  # plastic keeps diffuse_reflectance


def test_v05_names_substituted_from_defaults(tmp_path):
    text = V05.replace('<scene version="0.5.0">', '<scene version="0.5.0"><default name="myDepth" value="4"/>')
    text = text.replace('name="maxDepth" value="7"', 'name="maxDepth" value="$myDepth"')
    assert _load_text(tmp_path, "s.xml", text).max_depth == 4


def test_v3_file_is_not_upgraded(tmp_path):
    import pytest

    with pytest.warns(UserWarning, match="unused parameter 'toWorld'"):
        _load_text(tmp_path, "s.xml", V05.replace('version="0.5.0"', 'version="3.0.0"').replace("<lookAt", "<lookat"))


def test_scene_versions_refused(tmp_path):
    import pytest

    from restir.scene.errors import SceneError

    for version, match in ((None, "needs a version"), ("0.6", "major.minor.patch"), ("4.0.0", "newer")):
        text = V3.replace(' version="3.0.0"', "" if version is None else f' version="{version}"')
        with pytest.raises(SceneError, match=match):
            _load_text(tmp_path, "s.xml", text)


def test_high_quality_edges_warns(tmp_path):
    import pytest

    text = V05.replace('<string name="pixelFormat" value="rgb"/>', '<boolean name="highQualityEdges" value="true"/>')
    with pytest.warns(UserWarning, match="high_quality_edges"):
        _load_text(tmp_path, "s.xml", text)


def test_missing_texture_grey(tmp_path):
    import pytest

    from restir.scene.errors import SceneError

    xml = _scene('<bsdf type="diffuse"><texture type="bitmap" name="reflectance"><string name="filename" '
                 'value="gone.png"/></texture></bsdf>')
    (tmp_path / "scene.xml").write_text(xml)
    with pytest.raises(SceneError, match="texture file 'gone.png' not found"):
        restir.load_scene(str(tmp_path / "scene.xml"))
    with pytest.warns(UserWarning, match="gone.png' not found: rendered as constant grey"):
        scene = restir.load_scene(str(tmp_path / "scene.xml"), missing_textures="grey")
    np.testing.assert_array_equal(scene.textures[0].image, np.full((1, 1, 3), 0.5, np.float32))
    with pytest.raises(SceneError, match="missing_textures must be one of"):
        restir.load_scene(str(tmp_path / "scene.xml"), missing_textures="pink")


def test_a_mesh_without_uvs_has_barycentric_uvs(tmp_path):
    """Mitsuba 3's uv on a mesh without texture coordinates is the hit's barycentrics (b1, b2):
    (0, 0), (1, 0), (0, 1) at each triangle's corners, a quad's fan included; with vt, the file's."""
    (tmp_path / "a.obj").write_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n")
    (tmp_path / "b.obj").write_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nvt 0.1 0.2\nvt 0.3 0.4\nvt 0.5 0.6\nf 1/1 2/2 3/3\n")
    for name in ("a", "b"):
        (tmp_path / f"{name}.xml").write_text(_scene("").replace(
            '<shape type="rectangle"></shape>', f'<shape type="obj"><string name="filename" value="{name}.obj"/></shape>'))
    a = restir.load_scene(str(tmp_path / "a.xml"))
    np.testing.assert_array_equal(a.uvs.reshape(-1, 3, 2), [[[0, 0], [1, 0], [0, 1]]] * 2)
    b = restir.load_scene(str(tmp_path / "b.xml"))
    # OBJ's v is flipped (1 - v), as Mitsuba reads it
    np.testing.assert_allclose(b.uvs.reshape(-1, 3, 2), [[[0.1, 0.8], [0.3, 0.6], [0.5, 0.4]]], atol=1e-6)


def test_the_two_obj_readers_agree():
    """load_obj's numpy reader of regular files gives the line reader's mesh, array for array,
    and leaves every irregular file (negative indices, mixed corner formats, v with w) to it."""
    from restir.scene.shapes import _read_obj_lines, _read_obj_regular

    body = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\n# a comment\ng part\n"
    regular = [body + "f 1/1/1 2/2/1 3/3/1\nf 1/1/1 3/3/1 4/1/1\n",
               body + "f 1 2 3 4\n",
               body + "f 1//1 2//1 3//1 4//1\n",
               body + "f 1/1 2/2 3/3\ns off\nf 4/1 1/2 3/3\n"]
    for text in regular:
        fast, slow = _read_obj_regular(text), _read_obj_lines(text, "t.obj")
        assert fast is not None, text
        for a, b in zip(fast, slow):
            np.testing.assert_array_equal(a, b)
    irregular = [body + "f -4 -3 -2\n", body + "f 1/1 2 3/3/1\n", "v 0 0 0 1\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
                 body + "f 1 2 9\n", body + "f 0 1 2\n", body + "  f 1 2 3\n",
                 body + "vt 0 1 0\nf 1 2 3\n"]
    for text in irregular:
        assert _read_obj_regular(text) is None, text


def test_ply_triangles_and_polygons(tmp_path):
    """load_ply: a binary file of triangles (read as one array), one with a quad among them (the
    face-by-face read, fanned) and the same in ASCII all give the same fan triangulation."""
    from restir.scene.shapes import load_ply

    v = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1]], np.float32)
    header = ("ply\nformat {fmt} 1.0\nelement vertex 5\nproperty float x\nproperty float y\nproperty float z\n"
              "element face {n}\nproperty list uint8 int vertex_indices\nend_header\n")

    def write(name, faces, binary):
        with open(tmp_path / name, "wb") as f:
            f.write(header.format(fmt="binary_little_endian" if binary else "ascii", n=len(faces)).encode())
            if binary:
                f.write(v.tobytes())
                for face in faces:
                    f.write(bytes([len(face)]) + np.asarray(face, "<i4").tobytes())
            else:
                f.write("".join(" ".join(map(str, p)) + "\n" for p in v.tolist()).encode())
                f.write("".join(f"{len(face)} " + " ".join(map(str, face)) + "\n" for face in faces).encode())
        return load_ply(str(tmp_path / name), name).positions

    tris = [[0, 1, 2], [0, 2, 3], [1, 2, 4]]
    mixed = [[0, 1, 2, 3], [1, 2, 4]]  # the quad fans into the first two triangles
    expected = v[np.array(tris)]
    for got in (write("t.ply", tris, True), write("m.ply", mixed, True), write("a.ply", mixed, False)):
        np.testing.assert_array_equal(got, expected)
