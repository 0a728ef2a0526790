"""Small scene dicts and device-scene helpers for tests."""
import numpy as np
import warp as wp

import restir

from restir.scene.scene import build_scene
from restir.scene.upload import DeviceScene


def sensor(width=16, height=16, spp=4):
    from restir.scene.transforms import look_at

    return {"type": "perspective", "fov": 45.0, "to_world": look_at([0, 0, -3], [0, 0, 0], [0, 1, 0]),
            "film": {"type": "hdrfilm", "width": width, "height": height, "rfilter": {"type": "box"}},
            "sampler": {"type": "independent", "sample_count": spp}}


def triangle(v, radiance=None, bsdf=None):
    d = {"type": "trimesh", "vertices": np.asarray(v, float), "faces": np.array([[0, 1, 2]]),
         "bsdf": bsdf or {"type": "diffuse"}}
    if radiance is not None:
        d["emitter"] = {"type": "area", "radiance": {"type": "rgb", "value": radiance}}
    return d


def device_scene(tree: dict, device="cpu") -> DeviceScene:
    wp.init()
    return DeviceScene(build_scene(tree, "test"), device)


def half_dark_scene():
    """A floor lit by a light above it (facing down) and an equally bright light beside it facing
    up, at nothing: about half of all light candidates have zero contribution (the half-dark
    scene of docs/validation.md#level-3-stage-matrix, the target of defects A1 and A3). The camera
    looks at the floor from below the lights."""
    from restir.scene.transforms import look_at

    def quad(cx, y, s, up):
        a, b, c, d = [cx - s, y, -s], [cx + s, y, -s], [cx + s, y, s], [cx - s, y, s]
        tris = ([a, b, c], [a, c, d]) if up else ([a, c, b], [a, d, c])
        return [triangle(t, [10, 10, 10]) for t in tris]

    floor = [triangle([[-4, -1, -4], [4, -1, 4], [4, -1, -4]]), triangle([[-4, -1, -4], [-4, -1, 4], [4, -1, 4]])]
    parts = floor + quad(0.0, 1.5, 0.6, up=False) + quad(3.0, 1.5, 0.6, up=True)
    tree = {"type": "scene", "sensor": sensor(24, 24)}
    tree["sensor"]["to_world"] = look_at([0, 0.3, -3.0], [0, -1, 0.5], [0, 1, 0])
    tree.update({f"p{i}": part for i, part in enumerate(parts)})
    return build_scene(tree, "half-dark")


def shadow_scene():
    """A floor under a large, close area light with blinds (four slats) between them: the light is
    partly occluded almost everywhere, differently from pixel to pixel, and it is large enough
    that BSDF sampling finds it about as often as light sampling does (where BSDF candidates and
    visibility interact)."""
    from restir.scene.transforms import look_at

    def quad(y, s, radiance=None, down=True, z0=None, z1=None):
        z0, z1 = (-s, s) if z0 is None else (z0, z1)
        a, b, c, d = [-s, y, z0], [s, y, z0], [s, y, z1], [-s, y, z1]
        tris = ([a, b, c], [a, c, d]) if down else ([a, c, b], [a, d, c])  # normal cross(p1-p0, p2-p0)
        return [triangle(t, radiance) for t in tris]

    floor = quad(-1.0, 4.0, down=False)
    light = quad(1.2, 3.0, radiance=[2, 2, 2])
    slats = [t for z in (-1.2, -0.5, 0.2, 0.9) for t in quad(0.2, 1.5, z0=z, z1=z + 0.35)]
    plate = [dict(t, bsdf={"type": "twosided", "bsdf": {"type": "diffuse"}}) for t in slats]
    tree = {"type": "scene", "sensor": sensor(24, 24)}
    tree["sensor"]["to_world"] = look_at([0, 0.6, -3.0], [0, -1, 0.3], [0, 1, 0])
    tree.update({f"p{i}": part for i, part in enumerate(floor + light + plate)})
    return build_scene(tree, "shadow")


def feature_scene():
    """The feature scene (tests/data/feature_scene.py: every material kind, textures, the shapes)
    loaded from a fresh temporary folder."""
    import tempfile

    import restir
    from tests.data.feature_scene import write_feature_scene

    return restir.load_scene(write_feature_scene(tempfile.mkdtemp()))


def bump_scene():
    """The bump-map scene (tests/data/feature_scene.py: bumpmap around five BSDFs, a mesh without
    uvs), from a fresh temporary folder; its warning about Bitterli's unapplied wrapper (there
    on purpose) silenced."""
    import tempfile
    import warnings

    import restir
    from restir.scene.errors import SceneWarning
    from tests.data.feature_scene import write_bump_scene

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SceneWarning)
        return restir.load_scene(write_bump_scene(tempfile.mkdtemp()))


def feature_scene_named(name: str):
    """One of tests/data/feature_scene.py's SCENES, loaded from a fresh temporary folder."""
    import tempfile

    import restir
    from tests.data.feature_scene import SCENES

    return restir.load_scene(SCENES[name](tempfile.mkdtemp()))


def write_scene(tmp_path, bsdf_xml: str, image: np.ndarray | None = None, mode: str = "RGB", before: str = "") -> str:
    """A scene with one rectangle (z = 0, facing +z, uv (0, 0) at (-1, -1)) carrying bsdf_xml,
    after the top-level objects `before`."""
    from PIL import Image

    if image is not None:
        Image.fromarray(image, mode=mode).save(tmp_path / "h.png")
    (tmp_path / "s.xml").write_text(f"""<scene version="3.0.0">
        <sensor type="perspective"><float name="fov" value="40"/><film type="hdrfilm"><integer name="width" value="4"/>
            <integer name="height" value="4"/></film></sensor>{before}
        <shape type="rectangle">{bsdf_xml}</shape>
    </scene>""")
    return str(tmp_path / "s.xml")


def mask_scene():
    """The opacity-mask scene (tests/data/feature_scene.py: masks by texture and constant, around a
    bump map and two conductors), from a fresh temporary folder."""
    import tempfile

    import restir
    from tests.data.feature_scene import write_mask_scene

    return restir.load_scene(write_mask_scene(tempfile.mkdtemp()))


# one scene in both formats: the 0.5 text uses every rule of the upgrade
V05 = """<scene version="0.5.0">
    <integrator type="path"><integer name="maxDepth" value="7"/><integer name="rrDepth" value="3"/></integrator>
    <sensor type="perspective"><float name="fov" value="40"/><string name="fovAxis" value="y"/>
        <transform name="toWorld"><lookAt origin="0, 0, -4" target="0, 0, 0" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sampleCount" value="9"/></sampler>
        <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="6"/>
            <string name="pixelFormat" value="rgb"/></film>
    </sensor>
    <bsdf type="diffuse" id="checks"><texture type="checkerboard" name="diffuseReflectance">
        <float name="uscale" value="4"/><float name="voffset" value="0.25"/></texture></bsdf>
    <bsdf type="roughplastic" id="coat"><float name="intIOR" value="1.6"/><float name="extIOR" value="1.1"/>
        <rgb name="diffuseReflectance" value="0.2, 0.3, 0.4"/><float name="alpha" value="0.2"/></bsdf>
    <shape type="rectangle"><ref id="checks"/><transform name="toWorld"><translate x="0.5"/></transform></shape>
    <shape type="rectangle"><ref name="bsdf" id="coat"/><boolean name="flipNormals" value="true"/></shape>
</scene>"""
V3 = """<scene version="3.0.0">
    <integrator type="path"><integer name="max_depth" value="7"/><integer name="rr_depth" value="3"/></integrator>
    <sensor type="perspective"><float name="fov" value="40"/><string name="fov_axis" value="y"/>
        <transform name="to_world"><lookat origin="0, 0, -4" target="0, 0, 0" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="9"/></sampler>
        <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="6"/>
            <string name="pixel_format" value="rgb"/></film>
    </sensor>
    <bsdf type="diffuse" id="checks"><texture type="checkerboard" name="reflectance">
        <transform name="to_uv"><translate y="0.25"/><scale x="4"/></transform></texture></bsdf>
    <bsdf type="roughplastic" id="coat"><float name="int_ior" value="1.6"/><float name="ext_ior" value="1.1"/>
        <rgb name="diffuse_reflectance" value="0.2, 0.3, 0.4"/><float name="alpha" value="0.2"/></bsdf>
    <shape type="rectangle"><ref id="checks"/><transform name="to_world"><translate x="0.5"/></transform></shape>
    <shape type="rectangle"><ref name="bsdf" id="coat"/><boolean name="flip_normals" value="true"/></shape>
</scene>"""


# ------------------------------------------------------------------ scenes in motion (8 frames)
MOTION_KINDS = ("occluder", "light", "switch", "appear", "all")


def motion_scene(kind: str):
    """The Cornell box with one kind of motion over 8 frames, fast enough that every frame
    uncovers or covers pixels (at 32x32 a pixel is about 1.7 cm of the back wall):
    occluder: the short block slides 2.5 cm a frame toward the red wall (its shadow and the floor
    behind it move); light: the light swings 3 cm a frame along x and back; switch: the light is
    off in frames 3 and 4; appear: the tall block is gone (100 m below the floor) in frames 2 to 4;
    all: the four together."""
    from restir.scene.animation import Motion, animate

    scene = restir.load_scene("builtin:cornell-box")
    motions = {}
    if kind in ("occluder", "all"):
        motions["short"] = Motion(translation=([0, 7], [[0, 0, 0], [0.175, 0, -0.05]]))
    light = {}
    if kind in ("light", "all"):
        light["translation"] = ([0, 3, 7], [[-0.06, 0, 0], [0.03, 0, 0.02], [-0.09, 0, 0]])
    if kind in ("switch", "all"):
        light["emission"] = ([0, 3, 5], [[1.0], [0.0], [1.0]], "step")
    if light:
        motions["light"] = Motion(**light)
    if kind in ("appear", "all"):
        motions["tall"] = Motion(translation=([0, 2, 5], [[0, 0, 0], [0, -100, 0], [0, 0, 0]], "step"))
    return animate(scene, motions)
