"""Small scenes exercising what the shared scenes do not, for the Mitsuba 3 comparison.

- `write_feature_scene`: envmap (with to_world), bitmap texture, plastic, roughplastic (GGX and
  Beckmann), rough dielectric, GGX rough conductor, disk light (scene.xml, env.exr, checker.png);
- `write_texture_scene`: textures on every texturable parameter, as Bitterli's scenes use them:
  a checkerboard with `to_uv` on a rough conductor's specular_reflectance (Veach Ajar's floor),
  bitmaps with nearest and bilinear filtering, repeat, mirror and clamp wrapping and `to_uv`, on
  diffuse, plastic (diffuse and specular reflectance) and thindielectric (transmittance), all on
  rectangles (whose uv both renderers define alike);
- `write_bump_scene`: bump maps (`bumpmap`) as Bitterli's scenes use them and beyond: around a
  twosided rough plastic (the bathroom's floor), a diffuse, a mirror (a delta lobe), a twosided
  diffuse seen from its back with flip_invalid_normals and the shadowing term off, and a mesh
  without texture coordinates (barycentric uvs); grey (8-bit, sRGB) and coloured (luminance)
  height maps with `scale` and `to_uv`; and Bitterli's unreferenced wrapper, whose bump neither
  renderer applies;
- `write_normal_scene`: normal maps (`normalmap`) around a twosided rough plastic floor, a diffuse
  wall, a twosided diffuse seen from its back with flip_invalid_normals and the shadowing term
  off, a mirror (a delta lobe), and a mesh whose uvs are mirrored on some of its triangles (Mitsuba
  3's frame ignores the mirroring, and so does restir's without `uv_handed`); raw 8-bit maps,
  with `to_uv`; with a two-sided emitting panel (restir's extension), for the matrices;
- `write_mask_scene`: opacity masks (`mask`) as Bitterli's scenes use them and beyond: a leaf
  whose one coloured bitmap is both its reflectance and (by luminance) its opacity (the living
  room's plant), a constant opacity under the light (the kitchen's blinds: light reaches the floor
  below through it only by BSDF sampling, since a shadow ray stops at a mask in both renderers),
  a masked rug with a bump map over a floor of another colour, and masks around a rough and a
  smooth conductor (a delta lobe); the camera sees through the leaf (stochastic primary hits);
- `write_delta_scene`: Mitsuba 3's delta lights, a point, a spot (its linear falloff between
  beam_width and cutoff_angle) and a directional light, alone or mixed with an area light and a
  constant environment, over a diffuse floor, a rough conductor wall and a rough plastic sphere
  (whose shadows and glossy highlights show where each light is); `write_thinlens_scene`: the
  same room lit by its area light and the point light, seen through Mitsuba 3's thin lens;
- `write_material_scene`: the materials of the pbrt-v4 and glTF readers (restir's own plugins:
  metallic_roughness, mixture, a textured roughness, diffuse_transmission), for the matrices only.

Both the Mitsuba reference generator and the test call them, so they render identical inputs.
`SCENES` names them.
"""
import os

import numpy as np


def _header(fov: str, origin: str, target: str, lens: str = "") -> str:
    """The scene element's opening, defaults, integrator and sensor (48 x 36, box filter); lens:
    a thin lens's parameters (a perspective sensor without)."""
    sensor = f'thinlens">{lens}' if lens else 'perspective">'
    return f"""<scene version="3.0.0">
    <default name="spp" value="16"/>
    <default name="resx" value="48"/>
    <default name="resy" value="36"/>
    <default name="max_depth" value="5"/>
    <integrator type="path"><integer name="max_depth" value="$max_depth"/></integrator>
    <sensor type="{sensor}
        <float name="fov" value="{fov}"/>
        <string name="fov_axis" value="y"/>
        <transform name="to_world"><lookat origin="{origin}" target="{target}" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="$spp"/></sampler>
        <film type="hdrfilm"><integer name="width" value="$resx"/><integer name="height" value="$resy"/>
            <rfilter type="box"/></film>
    </sensor>
"""


SCENE = _header("50", "0, 1.2, -4", "0, 0.3, 0") + """    <emitter type="envmap">
        <string name="filename" value="env.exr"/>
        <float name="scale" value="1.5"/>
        <transform name="to_world"><rotate y="1" angle="40"/></transform>
    </emitter>
    <texture type="bitmap" id="checker"><string name="filename" value="checker.png"/></texture>
    <shape type="rectangle">
        <transform name="to_world"><scale value="3"/><rotate x="1" angle="-90"/></transform>
        <bsdf type="diffuse"><ref name="reflectance" id="checker"/></bsdf>
    </shape>
    <shape type="sphere">
        <point name="center" x="-1.1" y="0.6" z="0.2"/><float name="radius" value="0.6"/>
        <bsdf type="plastic"><rgb name="diffuse_reflectance" value="0.1, 0.3, 0.7"/></bsdf>
    </shape>
    <shape type="sphere">
        <point name="center" x="0.3" y="0.5" z="0.6"/><float name="radius" value="0.5"/>
        <bsdf type="roughdielectric"><float name="alpha" value="0.2"/><string name="distribution" value="ggx"/></bsdf>
    </shape>
    <shape type="cube">
        <transform name="to_world"><scale value="0.35"/><rotate y="1" angle="30"/><translate x="1.3" y="0.35" z="-0.3"/></transform>
        <bsdf type="roughconductor"><string name="distribution" value="ggx"/><float name="alpha" value="0.3"/>
            <rgb name="eta" value="0.2, 0.92, 1.1"/><rgb name="k" value="3.9, 2.45, 2.14"/></bsdf>
    </shape>
    <shape type="sphere">
        <point name="center" x="1.5" y="0.3" z="1.0"/><float name="radius" value="0.3"/>
        <bsdf type="roughplastic"><string name="distribution" value="ggx"/><float name="alpha" value="0.15"/>
            <rgb name="diffuse_reflectance" value="0.7, 0.2, 0.1"/></bsdf>
    </shape>
    <shape type="sphere">
        <point name="center" x="-0.4" y="0.25" z="-0.9"/><float name="radius" value="0.25"/>
        <bsdf type="roughplastic"><float name="alpha" value="0.3"/><rgb name="diffuse_reflectance" value="0.2, 0.6, 0.2"/></bsdf>
    </shape>
    <shape type="disk">
        <transform name="to_world"><scale value="0.4"/><rotate x="1" angle="90"/><translate x="0" y="2.5" z="0"/></transform>
        <emitter type="area"><rgb name="radiance" value="6, 5, 4"/></emitter>
    </shape>
</scene>
"""


def write_feature_scene(directory: str) -> str:
    from PIL import Image

    from restir.image_io import write_exr

    os.makedirs(directory, exist_ok=True)
    h, w = 128, 256
    v, u = np.mgrid[0:h, 0:w]
    theta, phi = (v + 0.5) / h * np.pi, (u + 0.5) / w * 2 * np.pi
    sky = np.stack([0.4 + 0.3 * np.cos(theta), 0.5 + 0.3 * np.cos(theta), 0.8 + 0.2 * np.cos(theta)], -1)
    sun = np.exp(-((theta - 0.7) ** 2 + (np.angle(np.exp(1j * (phi - 2.0)))) ** 2) / 0.05)[..., None] * np.array([8, 7, 5])
    write_exr(os.path.join(directory, "env.exr"), (sky * (theta < 1.6)[..., None] + sun).astype(np.float32))
    cv, cu = np.mgrid[0:16, 0:16]
    checker = np.where(((cu // 4 + cv // 4) % 2)[..., None] == 1, [200, 180, 150], [40, 60, 90]).astype(np.uint8)
    checker[:2, :2] = [255, 0, 0]  # marks the uv origin: a flipped axis shows up in the comparison
    Image.fromarray(checker).save(os.path.join(directory, "checker.png"))
    path = os.path.join(directory, "scene.xml")
    with open(path, "w") as f:
        f.write(SCENE)
    return path


TEXTURE_SCENE = _header("55", "0, 1.6, -4", "0, 0.6, 0") + """    <shape type="rectangle">
        <transform name="to_world"><scale value="3"/><rotate x="1" angle="-90"/></transform>
        <bsdf type="roughconductor"><float name="alpha" value="0.15"/><string name="distribution" value="ggx"/>
            <rgb name="eta" value="1.65746, 0.880369, 0.521229"/><rgb name="k" value="9.22387, 6.26952, 4.837"/>
            <texture name="specular_reflectance" type="checkerboard">
                <rgb name="color0" value="0.9, 0.8, 0.3"/><rgb name="color1" value="0.15, 0.2, 0.3"/>
                <transform name="to_uv"><scale x="4" y="8"/></transform>
            </texture>
        </bsdf>
    </shape>
    <shape type="rectangle">
        <transform name="to_world"><scale x="3" y="1.5"/><translate y="1.5" z="2"/></transform>
        <bsdf type="twosided"><bsdf type="diffuse">
            <texture name="reflectance" type="bitmap"><string name="filename" value="tiles.png"/>
                <string name="filter_type" value="nearest"/><string name="wrap_mode" value="mirror"/>
                <transform name="to_uv"><scale x="2.5" y="1.5"/></transform>
            </texture>
        </bsdf></bsdf>
    </shape>
    <shape type="rectangle">
        <transform name="to_world"><scale x="0.8" y="0.6"/><rotate y="1" angle="215"/><translate x="-1.3" y="0.7" z="0.4"/></transform>
        <bsdf type="plastic">
            <texture name="diffuse_reflectance" type="bitmap"><string name="filename" value="tiles.png"/>
                <string name="wrap_mode" value="clamp"/>
                <transform name="to_uv"><scale value="1.6"/><translate x="-0.3" y="-0.3"/></transform>
            </texture>
            <texture name="specular_reflectance" type="checkerboard">
                <rgb name="color0" value="1, 1, 1"/><rgb name="color1" value="0.3, 0.3, 0.3"/>
                <transform name="to_uv"><scale x="6" y="3"/></transform>
            </texture>
        </bsdf>
    </shape>
    <shape type="rectangle">
        <transform name="to_world"><scale x="0.7" y="0.7"/><rotate y="1" angle="-30"/><translate x="1.0" y="0.75" z="-0.6"/></transform>
        <bsdf type="thindielectric">
            <texture name="specular_transmittance" type="bitmap"><string name="filename" value="tiles.png"/>
                <boolean name="raw" value="true"/></texture>
        </bsdf>
    </shape>
    <shape type="disk">
        <transform name="to_world"><scale value="0.6"/><rotate x="1" angle="90"/><translate x="0" y="3" z="0"/></transform>
        <emitter type="area"><rgb name="radiance" value="9, 8, 7"/></emitter>
    </shape>
    <emitter type="constant"><rgb name="radiance" value="0.15, 0.18, 0.22"/></emitter>
</scene>
"""


def write_texture_scene(directory: str) -> str:
    from PIL import Image

    os.makedirs(directory, exist_ok=True)
    cv, cu = np.mgrid[0:8, 0:12]
    tiles = np.stack([40 + 200 * (cu / 11.0), 60 + 150 * (cv / 7.0), 220 - 20 * ((cu + cv) % 3)], -1).astype(np.uint8)
    tiles[0, 0] = [255, 0, 0]   # the uv origin and the far corner marked: a flipped or shifted
    tiles[-1, -1] = [0, 0, 0]   # axis, or a wrong wrap, shows up in the comparison
    Image.fromarray(tiles).save(os.path.join(directory, "tiles.png"))
    path = os.path.join(directory, "scene.xml")
    with open(path, "w") as f:
        f.write(TEXTURE_SCENE)
    return path


def _bump_map(tex: str, scale: float | None = None, extra: str = "") -> str:
    s = "" if scale is None else f'<float name="scale" value="{scale}"/>'
    return f'<texture name="map" type="bitmap"><string name="filename" value="{tex}"/>{extra}</texture>{s}'


BUMP_SCENE = _header("55", "0.3, 1.7, -4", "0, 0.6, 0") + f"""    <shape type="rectangle">
        <transform name="to_world"><scale value="3"/><rotate x="1" angle="-90"/></transform>
        <bsdf type="bumpmap">{_bump_map("tiles.png", 0.08, '<transform name="to_uv"><scale value="2"/></transform>')}
            <bsdf type="twosided"><bsdf type="roughplastic"><float name="alpha" value="0.2"/>
                <string name="distribution" value="ggx"/><rgb name="diffuse_reflectance" value="0.5, 0.45, 0.4"/>
            </bsdf></bsdf>
        </bsdf>
    </shape>
    <shape type="rectangle">
        <transform name="to_world"><scale x="3" y="1.5"/><rotate y="1" angle="180"/><translate y="1.5" z="2"/></transform>
        <bsdf type="bumpmap">{_bump_map("waves.png", 0.3)}
            <bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.6, 0.55"/></bsdf>
        </bsdf>
    </shape>
    <shape type="rectangle">
        <transform name="to_world"><scale x="1.5" y="1.5"/><rotate y="1" angle="-90"/><translate x="-2.2" y="1.5"/></transform>
        <bsdf type="bumpmap">{_bump_map("waves.png", 0.5)}
            <boolean name="flip_invalid_normals" value="false"/><boolean name="use_shadowing_function" value="false"/>
            <bsdf type="twosided"><bsdf type="diffuse"><rgb name="reflectance" value="0.3, 0.5, 0.7"/></bsdf></bsdf>
        </bsdf>
    </shape>
    <shape type="rectangle">
        <transform name="to_world"><scale x="0.6" y="0.5"/><rotate y="1" angle="200"/><translate x="1.3" y="0.8" z="0.5"/></transform>
        <bsdf type="bumpmap">{_bump_map("waves.png", 0.05)}
            <bsdf type="conductor"><rgb name="eta" value="0.2, 0.92, 1.1"/><rgb name="k" value="3.9, 2.45, 2.14"/></bsdf>
        </bsdf>
    </shape>
    <shape type="obj">
        <string name="filename" value="tent.obj"/>
        <transform name="to_world"><scale value="0.5"/><translate x="-0.8" y="0.01" z="-0.4"/></transform>
        <bsdf type="bumpmap">{_bump_map("tiles.png", 0.02, '<transform name="to_uv"><scale value="3"/></transform>')}
            <bsdf type="diffuse"><rgb name="reflectance" value="0.7, 0.3, 0.2"/></bsdf>
        </bsdf>
    </shape>
    <bsdf type="bumpmap">{_bump_map("tiles.png")}
        <bsdf type="twosided" id="unapplied"><bsdf type="diffuse"><rgb name="reflectance" value="0.2, 0.6, 0.3"/></bsdf></bsdf>
    </bsdf>
    <shape type="rectangle">
        <transform name="to_world"><scale x="0.5" y="0.4"/><translate x="0.4" y="0.4" z="1.2"/></transform>
        <ref id="unapplied"/>
    </shape>
    <shape type="rectangle">
        <transform name="to_world"><scale value="0.6"/><rotate x="1" angle="90"/><translate x="0.5" y="3" z="-0.5"/></transform>
        <emitter type="area"><rgb name="radiance" value="9, 8, 7"/></emitter>
    </shape>
    <emitter type="constant"><rgb name="radiance" value="0.1, 0.12, 0.15"/></emitter>
</scene>
"""

# a four-sided tent without texture coordinates: its uvs are each triangle's barycentrics
TENT_OBJ = """v -1 0 -1
v 1 0 -1
v 1 0 1
v -1 0 1
v 0 1.2 0
f 1 5 2
f 2 5 3
f 3 5 4
f 4 5 1
"""


def write_bump_scene(directory: str) -> str:
    from PIL import Image

    os.makedirs(directory, exist_ok=True)
    y, x = (np.mgrid[0:32, 0:32] + 0.5) / 8.0
    fx, fy = x - np.floor(x), y - np.floor(y)  # 8x8-texel tiles, grout at their edges
    tile = np.clip(np.minimum(np.minimum(fx, 1 - fx), np.minimum(fy, 1 - fy)) * 6.0, 0.0, 1.0)
    Image.fromarray((40 + 200 * tile).astype(np.uint8), mode="L").save(os.path.join(directory, "tiles.png"))
    v, u = (np.mgrid[0:24, 0:40] + 0.5) / np.array([24.0, 40.0])[:, None, None]
    waves = np.stack([0.5 + 0.5 * np.sin(2 * np.pi * (3 * u + v)), 0.5 + 0.4 * np.sin(2 * np.pi * 2 * v),
                      0.5 + 0.5 * np.cos(2 * np.pi * (u - 2 * v))], -1)
    Image.fromarray((255 * waves).astype(np.uint8)).save(os.path.join(directory, "waves.png"))
    with open(os.path.join(directory, "tent.obj"), "w") as f:
        f.write(TENT_OBJ)
    path = os.path.join(directory, "scene.xml")
    with open(path, "w") as f:
        f.write(BUMP_SCENE)
    return path


MIRROR = '<bsdf type="conductor"><rgb name="eta" value="0.2, 0.92, 1.1"/><rgb name="k" value="3.9, 2.45, 2.14"/></bsdf>'


def _normal_map(tex: str, extra: str = "") -> str:
    return (f'<texture name="normalmap" type="bitmap"><string name="filename" value="{tex}"/>'
            f'<boolean name="raw" value="true"/>{extra}</texture>')


NORMAL_SCENE = _header("55", "0.3, 1.7, -4", "0, 0.6, 0") + f"""    <shape type="rectangle">
        <transform name="to_world"><scale value="3"/><rotate x="1" angle="-90"/></transform>
        <bsdf type="normalmap">{_normal_map("tiles_n.png", '<transform name="to_uv"><scale value="2"/></transform>')}
            <bsdf type="twosided"><bsdf type="roughplastic"><float name="alpha" value="0.2"/>
                <string name="distribution" value="ggx"/><rgb name="diffuse_reflectance" value="0.5, 0.45, 0.4"/>
            </bsdf></bsdf>
        </bsdf>
    </shape>
    <shape type="rectangle">
        <transform name="to_world"><scale x="3" y="1.5"/><rotate y="1" angle="180"/><translate y="1.5" z="2"/></transform>
        <bsdf type="normalmap">{_normal_map("waves_n.png")}
            <bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.6, 0.55"/></bsdf>
        </bsdf>
    </shape>
    <shape type="rectangle">
        <transform name="to_world"><scale x="1.5" y="1.5"/><rotate y="1" angle="-90"/><translate x="-2.2" y="1.5"/></transform>
        <bsdf type="normalmap">{_normal_map("waves_n.png")}
            <boolean name="flip_invalid_normals" value="false"/><boolean name="use_shadowing_function" value="false"/>
            <bsdf type="twosided"><bsdf type="diffuse"><rgb name="reflectance" value="0.3, 0.5, 0.7"/></bsdf></bsdf>
        </bsdf>
    </shape>
    <shape type="rectangle">
        <transform name="to_world"><scale x="0.6" y="0.5"/><rotate y="1" angle="200"/><translate x="1.3" y="0.8" z="0.5"/></transform>
        <bsdf type="normalmap">{_normal_map("tiles_n.png")}
            {MIRROR}
        </bsdf>
    </shape>
    <shape type="obj">
        <string name="filename" value="tent_uv.obj"/>
        <transform name="to_world"><scale value="0.5"/><translate x="-0.8" y="0.01" z="-0.4"/></transform>
        <bsdf type="normalmap">{_normal_map("waves_n.png")}
            <bsdf type="diffuse"><rgb name="reflectance" value="0.7, 0.3, 0.2"/></bsdf>
        </bsdf>
    </shape>
    <shape type="rectangle">
        <transform name="to_world"><scale value="0.6"/><rotate x="1" angle="90"/><translate x="0.5" y="3" z="-0.5"/></transform>
        <emitter type="area"><rgb name="radiance" value="9, 8, 7"/></emitter>
    </shape>
    <emitter type="constant"><rgb name="radiance" value="0.1, 0.12, 0.15"/></emitter>
</scene>
"""

# the tent again, with texture coordinates: two faces mapped as the image stands, two mirrored
TENT_UV_OBJ = TENT_OBJ.split("f ")[0] + """vt 0 0
vt 1 0
vt 0.5 1
f 1/1 5/3 2/2
f 2/2 5/3 3/1
f 3/1 5/3 4/2
f 4/2 5/3 1/1
"""


def _encode_normals(n: np.ndarray) -> np.ndarray:
    """Unit normals (H, W, 3) as an 8-bit normal map, (n + 1) / 2."""
    n = n / np.linalg.norm(n, axis=-1, keepdims=True)
    return np.clip(np.round((n + 1) * 127.5), 0, 255).astype(np.uint8)


# a panel that lights both ways (restir's `twosided` area emitter: pbrt-v4's two-sided area lights,
# glTF's double-sided emissive materials), standing between the camera and the back wall
TWOSIDED_PANEL = """    <shape type="rectangle">
        <transform name="to_world"><scale x="0.35" y="0.5"/><rotate y="1" angle="150"/><translate x="0.6" y="0.7" z="1.1"/></transform>
        <emitter type="area"><rgb name="radiance" value="3, 4, 6"/><boolean name="twosided" value="true"/></emitter>
    </shape>
"""


def write_normal_scene(directory: str, twosided_panel: bool = False) -> str:
    """The normal-map scene; with `twosided_panel`, also TWOSIDED_PANEL (for the matrices: restir's
    own emitter, so no Mitsuba 3 reference)."""
    from PIL import Image

    os.makedirs(directory, exist_ok=True)
    y, x = (np.mgrid[0:32, 0:32] + 0.5) / 8.0
    fx, fy = x - np.floor(x), y - np.floor(y)  # 8x8-texel tiles, bevelled toward their grout
    gx = np.where(fx < 0.2, -1.0, np.where(fx > 0.8, 1.0, 0.0))
    gy = np.where(fy < 0.2, -1.0, np.where(fy > 0.8, 1.0, 0.0))
    tiles = np.stack([0.8 * gx, 0.8 * gy, np.ones_like(gx)], -1)
    Image.fromarray(_encode_normals(tiles)).save(os.path.join(directory, "tiles_n.png"))
    v, u = (np.mgrid[0:24, 0:40] + 0.5) / np.array([24.0, 40.0])[:, None, None]
    waves = np.stack([0.6 * np.sin(2 * np.pi * (3 * u + v)), 0.4 * np.cos(2 * np.pi * 2 * v), np.ones_like(u)], -1)
    Image.fromarray(_encode_normals(waves)).save(os.path.join(directory, "waves_n.png"))
    with open(os.path.join(directory, "tent_uv.obj"), "w") as f:
        f.write(TENT_UV_OBJ)
    path = os.path.join(directory, "scene.xml")
    text = NORMAL_SCENE
    if twosided_panel:
        # the mirror made rough: through the smooth one the tiles' bevels focus the light into
        # caustics that the path tracer's own 1-spp runs resolve only in hundreds of runs (at two
        # pixels: batch skewness 4-6, 64 runs' mean 35% under 512 runs'), which a cell's K of 64
        # cannot judge; smooth mirrors under normal maps are in the Mitsuba 3 comparison
        text = text.replace(MIRROR, '<bsdf type="roughconductor"><string name="distribution" value="ggx"/>'
                            '<float name="alpha" value="0.2"/>' + MIRROR[len('<bsdf type="conductor">'):])
        text = text.replace("</scene>", TWOSIDED_PANEL + "</scene>")
    with open(path, "w") as f:
        f.write(text)
    return path


MASK_SCENE = _header("55", "0.2, 1.4, -4", "0, 0.7, 0") + f"""    <shape type="rectangle">
        <transform name="to_world"><scale value="3"/><rotate x="1" angle="-90"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.25, 0.4, 0.6"/></bsdf>
    </shape>
    <shape type="rectangle">
        <transform name="to_world"><scale x="3" y="1.5"/><rotate y="1" angle="180"/><translate y="1.5" z="2"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.6, 0.55"/></bsdf>
    </shape>
    <shape type="rectangle">
        <transform name="to_world"><scale x="0.9" y="0.7"/><rotate y="1" angle="160"/><translate x="-0.6" y="0.9" z="-1.6"/></transform>
        <bsdf type="mask">
            <texture name="opacity" type="bitmap"><string name="filename" value="leaf.png"/></texture>
            <bsdf type="twosided"><bsdf type="diffuse">
                <texture name="reflectance" type="bitmap"><string name="filename" value="leaf.png"/></texture>
            </bsdf></bsdf>
        </bsdf>
    </shape>
    <shape type="rectangle">
        <transform name="to_world"><scale x="0.8" y="0.8"/><rotate x="1" angle="90"/><translate x="0.9" y="1.8" z="0.6"/></transform>
        <bsdf type="mask"><float name="opacity" value="0.6"/>
            <bsdf type="twosided"><bsdf type="diffuse"><rgb name="reflectance" value="0.61, 0.5, 0.38"/></bsdf></bsdf>
        </bsdf>
    </shape>
    <shape type="rectangle">
        <transform name="to_world"><scale x="1.2" y="0.8"/><rotate x="1" angle="-90"/><translate x="-0.5" y="0.01" z="0.6"/></transform>
        <bsdf type="mask">
            <texture name="opacity" type="bitmap"><string name="filename" value="stripes.png"/></texture>
            <bsdf type="bumpmap">{_bump_map("stripes.png", 0.1)}
                <bsdf type="twosided"><bsdf type="roughplastic"><float name="alpha" value="0.25"/>
                    <rgb name="diffuse_reflectance" value="0.7, 0.3, 0.2"/></bsdf></bsdf>
            </bsdf>
        </bsdf>
    </shape>
    <shape type="sphere">
        <point name="center" x="1.3" y="0.45" z="-0.2"/><float name="radius" value="0.45"/>
        <bsdf type="mask"><float name="opacity" value="0.5"/>
            <bsdf type="roughconductor"><string name="distribution" value="ggx"/><float name="alpha" value="0.3"/>
                <rgb name="eta" value="0.2, 0.92, 1.1"/><rgb name="k" value="3.9, 2.45, 2.14"/></bsdf>
        </bsdf>
    </shape>
    <shape type="rectangle">
        <transform name="to_world"><scale x="0.5" y="0.4"/><rotate y="1" angle="200"/><translate x="-1.5" y="1.1" z="1.3"/></transform>
        <bsdf type="mask"><float name="opacity" value="0.7"/>
            <bsdf type="conductor"><rgb name="eta" value="0.2, 0.92, 1.1"/><rgb name="k" value="3.9, 2.45, 2.14"/></bsdf>
        </bsdf>
    </shape>
    <shape type="rectangle">
        <transform name="to_world"><scale value="0.6"/><rotate x="1" angle="90"/><translate x="0.5" y="3" z="-0.5"/></transform>
        <emitter type="area"><rgb name="radiance" value="24, 21, 18"/></emitter>
    </shape>
    <emitter type="constant"><rgb name="radiance" value="0.1, 0.12, 0.15"/></emitter>
</scene>
"""


def write_mask_scene(directory: str) -> str:
    from PIL import Image

    os.makedirs(directory, exist_ok=True)
    # a leaf: opaque green inside an ellipse with a soft edge, a darker vein, transparent outside
    v, u = (np.mgrid[0:32, 0:48] + 0.5) / np.array([32.0, 48.0])[:, None, None]
    r = np.sqrt(((u - 0.5) / 0.45) ** 2 + ((v - 0.5) / 0.3) ** 2)
    inside = np.clip((1.0 - r) * 6.0, 0.0, 1.0)
    vein = 1.0 - 0.5 * np.exp(-((v - 0.5) / 0.04) ** 2)
    leaf = np.stack([0.35 * inside * vein, 0.95 * inside * vein, 0.3 * inside], -1)
    Image.fromarray((255 * leaf).astype(np.uint8)).save(os.path.join(directory, "leaf.png"))
    # soft stripes (grey, 8-bit sRGB): the rug's opacity and its height
    x = (np.mgrid[0:16, 0:40][1] + 0.5) / 40.0
    stripes = np.clip(0.5 + 0.7 * np.sin(2 * np.pi * 5 * x), 0.0, 1.0) * np.ones((16, 1))
    Image.fromarray((255 * stripes).astype(np.uint8), mode="L").save(os.path.join(directory, "stripes.png"))
    path = os.path.join(directory, "scene.xml")
    with open(path, "w") as f:
        f.write(MASK_SCENE)
    return path


DELTA_ROOM = """    <shape type="rectangle">
        <transform name="to_world"><scale value="3"/><rotate x="1" angle="-90"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.6, 0.6"/></bsdf>
    </shape>
    <shape type="rectangle">
        <transform name="to_world"><scale value="3"/><translate z="2"/></transform>
        <bsdf type="roughconductor"><float name="alpha" value="0.3"/></bsdf>
    </shape>
    <shape type="sphere">
        <point name="center" value="-0.6, 0.5, 0.3"/><float name="radius" value="0.5"/>
        <bsdf type="roughplastic"><rgb name="diffuse_reflectance" value="0.2, 0.4, 0.8"/></bsdf>
    </shape>
"""
DELTA_LIGHTS = {
    "area": """    <shape type="rectangle">
        <transform name="to_world"><scale value="0.2"/><rotate x="1" angle="90"/><translate x="1" y="2"/></transform>
        <emitter type="area"><rgb name="radiance" value="5, 5, 5"/></emitter>
    </shape>
""",
    "env": """    <emitter type="constant"><rgb name="radiance" value="0.05, 0.06, 0.08"/></emitter>
""",
    "point": """    <emitter type="point"><point name="position" value="0.8, 1.2, -0.5"/><rgb name="intensity" value="2, 1.5, 1"/></emitter>
""",
    "spot": """    <emitter type="spot">
        <transform name="to_world"><lookat origin="-1, 2.2, -1" target="-0.5, 0, 0.5" up="0, 1, 0"/></transform>
        <rgb name="intensity" value="6, 6, 8"/><float name="cutoff_angle" value="25"/><float name="beam_width" value="12"/>
    </emitter>
""",
    "directional": """    <emitter type="directional"><vector name="direction" value="1, -2, 1.5"/><rgb name="irradiance" value="0.8, 0.7, 0.5"/></emitter>
""",
}


def write_delta_scene(directory: str, lights=("point", "spot", "directional", "area", "env"), lens: str = "") -> str:
    os.makedirs(directory, exist_ok=True)
    path = os.path.join(directory, "scene.xml")
    with open(path, "w") as f:
        f.write(_header("50", "0, 1.5, -4", "0, 0.5, 0", lens) + DELTA_ROOM + "".join(DELTA_LIGHTS[k] for k in lights)
                + "</scene>\n")
    return path


def write_thinlens_scene(directory: str) -> str:
    lens = '<float name="aperture_radius" value="0.15"/><float name="focus_distance" value="3.5"/>'
    return write_delta_scene(directory, ("point", "area"), lens)


MATERIAL_ROOM = """    <texture type="bitmap" id="stripes"><string name="filename" value="stripes.png"/><boolean name="raw" value="true"/>
        <string name="filter_type" value="nearest"/></texture>
    <shape type="rectangle">
        <transform name="to_world"><scale value="3"/><rotate x="1" angle="-90"/></transform>
        <bsdf type="metallic_roughness"><rgb name="base_color" value="0.6, 0.55, 0.5"/><float name="metallic" value="0"/>
            <float name="roughness" value="0.5"/></bsdf>
    </shape>
    <shape type="rectangle">
        <transform name="to_world"><scale value="3"/><translate z="2"/></transform>
        <bsdf type="roughconductor"><string name="distribution" value="ggx"/><ref name="alpha" id="stripes"/>
            <boolean name="remap_roughness" value="true"/></bsdf>
    </shape>
    <shape type="sphere">
        <point name="center" value="-0.6, 0.5, 0.3"/><float name="radius" value="0.5"/>
        <bsdf type="mixture">
            <bsdf name="bsdf_a" type="metallic_roughness"><rgb name="base_color" value="1.0, 0.78, 0.34"/>
                <float name="metallic" value="1"/><float name="roughness" value="0.45"/></bsdf>
            <bsdf name="bsdf_b" type="diffuse"><rgb name="reflectance" value="0.2, 0.4, 0.8"/></bsdf>
            <ref name="amount" id="stripes"/>
        </bsdf>
    </shape>
    <shape type="sphere">
        <point name="center" value="0.8, 0.35, -0.3"/><float name="radius" value="0.35"/>
        <bsdf type="twosided"><bsdf type="metallic_roughness"><rgb name="base_color" value="0.8, 0.2, 0.1"/>
            <float name="metallic" value="0.5"/><float name="roughness" value="0.6"/></bsdf></bsdf>
    </shape>
    <shape type="rectangle">
        <transform name="to_world"><scale value="0.45"/><rotate x="1" angle="-60"/><translate x="0.3" y="1.0" z="-0.9"/></transform>
        <bsdf type="diffuse_transmission"><rgb name="reflectance" value="0.3, 0.5, 0.2"/>
            <rgb name="transmittance" value="0.4, 0.6, 0.2"/></bsdf>
    </shape>
"""


def write_material_scene(directory: str) -> str:
    """glTF's metallic-roughness BSDF (a rough non-metal floor, a half-metal sphere), a rough
    conductor whose pbrt-v4 roughness is a texture (stripes of roughness 0.04 and 0.36: alpha 0.2
    and 0.6), a per-point mixture of a gold metallic-roughness and a blue diffuse by the same
    stripes, and pbrt-v4's diffuse transmission on a tilted leaf between the lights and the
    floor, lit by the area light and the point light: the materials the pbrt-v4 and glTF
    readers add, for the matrices (restir's own plugins, so no Mitsuba 3 reference)."""
    from PIL import Image

    os.makedirs(directory, exist_ok=True)
    stripes = np.where((np.arange(8) // 2) % 2 == 0, 0.04, 0.36)
    img = np.repeat(np.tile(stripes, (8, 1))[..., None], 3, axis=2)
    Image.fromarray((img * 255 + 0.5).astype(np.uint8)).save(os.path.join(directory, "stripes.png"))
    path = os.path.join(directory, "scene.xml")
    with open(path, "w") as f:
        f.write(_header("50", "0, 1.5, -4", "0, 0.5, 0") + MATERIAL_ROOM + DELTA_LIGHTS["area"] + DELTA_LIGHTS["point"]
                + "</scene>\n")
    return path


SCENES = {"features": write_feature_scene, "materials": write_material_scene, "textures": write_texture_scene, "bumps": write_bump_scene,
          "normalmaps": write_normal_scene,
          "normalmaps-twosided": lambda d: write_normal_scene(d, twosided_panel=True),
          "masks": write_mask_scene, "delta-lights": write_delta_scene, "thinlens": write_thinlens_scene,
          # the delta lights alone: points and spots (no other light), and the sun
          "delta-only": lambda d: write_delta_scene(d, ("point", "spot")),
          "sun": lambda d: write_delta_scene(d, ("directional",)),
          # the delta-light scene again, for a Mitsuba 3 reference of its direct light (max_depth 2)
          "delta-lights-direct": write_delta_scene}
