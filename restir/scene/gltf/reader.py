"""glTF 2.0 scenes (docs/guide/gltf.md): the default scene's node hierarchy (matrices or
translation, rotation and scale), its meshes' triangle primitives (POSITION, NORMAL, TEXCOORD_0,
indices), a camera (the first, or the one named), KHR_lights_punctual, and the materials
(materials.py), translated into the Mitsuba-style scene object scene.build_scene builds.

Conventions: glTF is right-handed with +Y up; a camera looks down its -Z with +X to the image's
right, and a light shines down its -Z. restir's camera (Mitsuba's) looks down +Z with +X to the
left, so its world transform is the node's times diag(-1, 1, -1). Texture coordinates have
(0, 0) at the image's top-left corner, as restir's: they are used as they are.
"""
import math

import numpy as np

from ..errors import SceneError, warn
from ..scene_file import check_scene_file
from ..shapes import TriMesh
from ..transforms import frame_along
from .accessors import Buffers
from .animation import DEFAULT_FPS, read_animations
from .materials import Materials

KNOWN_EXTENSIONS = ("KHR_lights_punctual", "KHR_materials_emissive_strength", "KHR_texture_transform",
                    "KHR_materials_transmission", "KHR_materials_ior", "KHR_mesh_quantization")
DEFAULT_HEIGHT = 720
DEFAULT_YFOV = math.radians(45.0)


def load_gltf(path: str, camera: str | None = None, fps: float = DEFAULT_FPS) -> dict:
    try:
        import pygltflib
    except ImportError:
        raise SceneError("reading glTF needs the package pygltflib (pip install pygltflib)", path) from None
    check_scene_file(path)
    try:
        gltf = pygltflib.GLTF2().load(path)
    except Exception as e:  # the library raises many types for malformed JSON or GLB
        raise SceneError(f"not a readable glTF file ({type(e).__name__}: {e})", path) from None
    if gltf is None:
        raise SceneError("not a readable glTF file", path)
    return _Reader(gltf, path, camera, fps).read()


def _trs(node) -> np.ndarray:
    if node.matrix is not None and len(node.matrix) == 16:
        return np.array(node.matrix, float).reshape(4, 4).T  # column-major
    m = np.eye(4)
    if node.scale is not None:
        m = np.diag([*node.scale, 1.0]) @ m
    if node.rotation is not None:
        x, y, z, w = node.rotation
        n = math.sqrt(x * x + y * y + z * z + w * w) or 1.0
        x, y, z, w = x / n, y / n, z / n, w / n
        r = np.eye(4)
        r[:3, :3] = [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]
        m = r @ m
    if node.translation is not None:
        t = np.eye(4)
        t[:3, 3] = node.translation
        m = t @ m
    return m


class _Reader:
    def __init__(self, gltf, path: str, camera: str | None, fps: float = DEFAULT_FPS):
        self.gltf, self.path, self.camera_name, self.fps = gltf, path, camera, fps
        self.parents: dict[int, int] = {}  # node -> its parent (-1: a root)
        self.node_of: dict[str, int] = {}  # object name (the tree's key) -> the node that carries it
        self.buffers = Buffers(gltf, path)
        self.materials = Materials(gltf, self.buffers, path)
        self.shapes: list[dict] = []
        self.emitters: list[dict] = []
        self.cameras: list[tuple] = []   # (name, camera index, world matrix, node)
        self.camera_node = None          # the node of the camera the scene is seen through
        self.positions: list[tuple] = []  # (POSITION accessor, node matrix, name): the default view's bounds

    def read(self) -> dict:
        g = self.gltf
        for ext in g.extensionsRequired or []:
            if ext not in KNOWN_EXTENSIONS:
                raise SceneError(f"the file requires the extension '{ext}', which restir does not read", self.path)
        for ext in g.extensionsUsed or []:
            if ext not in KNOWN_EXTENSIONS:
                warn(f"the extension '{ext}' is not read (the file does not require it)", self.path)
        scenes = g.scenes or []
        if not scenes:
            raise SceneError("the file has no scene", self.path)
        scene = scenes[g.scene or 0] if (g.scene or 0) < len(scenes) else None
        if scene is None:
            raise SceneError(f"the default scene {g.scene} does not exist", self.path)
        seen: set[int] = set()
        for n in scene.nodes or []:
            self.parents[n] = -1
            self.node(n, np.eye(4), seen, 0)
        if not self.shapes:
            raise SceneError("the scene has no triangles", self.path)
        tree = {"type": "scene", "_loc": self.path, "_base_dir": self.buffers.base_dir, "sensor": self.sensor()}
        for i, s in enumerate(self.shapes):
            tree[f"shape_{i}"] = s
        for i, e in enumerate(self.emitters):
            tree[f"emitter_{i}"] = e
        parents = [self.parents.get(n, -1) for n in range(len(g.nodes or []))]
        tree["_animation"] = read_animations(g, self.buffers, parents, self.node_of, self.fps, self.path,
                                             self.camera_node)
        return tree

    # ------------------------------------------------------------------ graph
    def node(self, i: int, parent: np.ndarray, seen: set, depth: int) -> None:
        nodes = self.gltf.nodes or []
        if not 0 <= i < len(nodes):
            raise SceneError(f"node {i} does not exist", self.path)
        if i in seen or depth > 256:
            raise SceneError(f"node {i} is reached twice (the node graph is not a tree)", self.path)
        seen.add(i)
        node = nodes[i]
        m = parent @ _trs(node)
        if not np.all(np.isfinite(m)):
            raise SceneError(f"node {i}: its transform is not finite", self.path)
        if node.mesh is not None:
            if node.skin is not None:
                warn(f"node {i}: its skin is not applied (the mesh renders in its bind pose)", self.path)
            first = len(self.shapes)
            self.mesh(node.mesh, m if node.skin is None else np.eye(4))
            self.node_of.update({f"shape_{k}": i for k in range(first, len(self.shapes))})
        if node.camera is not None:
            self.cameras.append((node.name, node.camera, m, i))
        light = (node.extensions or {}).get("KHR_lights_punctual")
        if light is not None:
            self.light(light.get("light"), m, i)
            self.node_of[f"emitter_{len(self.emitters) - 1}"] = i
        for c in node.children or []:
            self.parents[c] = i
            self.node(c, m, seen, depth + 1)

    # ------------------------------------------------------------------ meshes
    def mesh(self, mi: int, m: np.ndarray) -> None:
        meshes = self.gltf.meshes or []
        if not 0 <= mi < len(meshes):
            raise SceneError(f"mesh {mi} does not exist", self.path)
        if abs(np.linalg.det(m[:3, :3])) <= 1e-30:
            raise SceneError(f"mesh {mi}: its node's transform is singular", self.path)
        for pi, prim in enumerate(meshes[mi].primitives):
            what = f"mesh {mi} primitive {pi}"
            mode = 4 if prim.mode is None else prim.mode
            if mode not in (4, 5, 6):
                warn(f"{what}: mode {mode} (points or lines) has no surface and is left out", self.path)
                continue
            if prim.targets:
                warn(f"{what}: morph targets are not applied", self.path)
            attrs = prim.attributes
            if attrs.POSITION is None:
                raise SceneError(f"{what} has no POSITION", self.path)
            if attrs.COLOR_0 is not None:
                warn(f"{what}: its vertex colours (COLOR_0) are not applied to the base colour", self.path)
            bsdf, emission, emission_tex = self.materials.material(prim.material)
            self.positions.append((attrs.POSITION, m, what))
            tangents = attrs.TANGENT is not None and self.materials.normal_mapped(prim.material)
            shape = {"type": "triangles", "load": self._loader(what, prim, mode, m, emission_tex, emission, tangents),
                     "bsdf": bsdf, "_loc": self.path}
            if np.any(emission > 0):
                # a double-sided material lights its back face too (its normals reversed there)
                shape["emitter"] = {"type": "area", "radiance": emission, "_loc": self.path,
                                    "twosided": self.materials.double_sided(prim.material)}
            self.shapes.append(shape)

    def _loader(self, what, prim, mode, m, emission_tex, emission, read_tangents=False):
        def load() -> TriMesh:
            a = prim.attributes
            p = self.buffers.accessor(a.POSITION, what)
            if p.shape[1] != 3:
                raise SceneError(f"{what}: POSITION is not VEC3", self.path)
            n = self.buffers.accessor(a.NORMAL, what) if a.NORMAL is not None else None
            uv = self.buffers.accessor(a.TEXCOORD_0, what) if a.TEXCOORD_0 is not None else None
            if prim.indices is not None:
                idx = self.buffers.accessor(prim.indices, what).reshape(-1)
                if idx.dtype.kind == "f":
                    raise SceneError(f"{what}: its indices are not integers", self.path)
            else:
                idx = np.arange(len(p))
            if len(idx) and (idx.min() < 0 or idx.max() >= len(p)):
                raise SceneError(f"{what}: an index refers to vertex {int(idx.max())}, but there are {len(p)}",
                                 self.path)
            if mode == 4:
                f = idx[:len(idx) - len(idx) % 3].reshape(-1, 3)
            elif mode == 5:  # strip: every other triangle reversed to keep the winding
                k = np.arange(max(len(idx) - 2, 0))
                f = np.stack([idx[k], idx[k + 1 + k % 2], idx[k + 2 - k % 2]], 1)
            else:  # fan
                k = np.arange(1, max(len(idx) - 1, 1))
                f = np.stack([np.full(len(k), idx[0]), idx[k], idx[k + 1]], 1) if len(idx) >= 3 else np.zeros((0, 3), int)
            if len(f) == 0:
                raise SceneError(f"{what} has no triangles", self.path)
            pos = p[f] @ m[:3, :3].T + m[:3, 3]
            nrm = None
            if n is not None:
                inv_t = np.linalg.inv(m[:3, :3]).T
                nn = n[:, :3] @ inv_t.T
                nn /= np.maximum(np.linalg.norm(nn, axis=1, keepdims=True), 1e-30)
                nrm = nn[f]
            uvs = uv[f][..., :2] if uv is not None else np.zeros((len(f), 3, 2))
            tan = None
            if read_tangents:  # a normal map's tangent (xyz, a direction on the surface) and bitangent sign
                t = self.buffers.accessor(a.TANGENT, what)
                if t.shape[1] != 4 or len(t) != len(p):
                    raise SceneError(f"{what}: TANGENT is not a VEC4 per vertex", self.path)
                tan = np.concatenate([t[:, :3] @ m[:3, :3].T, np.sign(t[:, 3:4]) + (t[:, 3:4] == 0)], 1)[f]
                if np.linalg.det(m[:3, :3]) < 0:  # a mirror turns the bitangent's handedness
                    tan[..., 3] *= -1
            if np.linalg.det(m[:3, :3]) < 0:  # a mirroring node keeps the front face (glTF: by the winding)
                pos, uvs = pos[:, ::-1], uvs[:, ::-1]
                nrm = nrm[:, ::-1] if nrm is not None else None
                tan = tan[:, ::-1] if tan is not None else None
            per_tri = None
            if emission_tex is not None:
                per_tri = emission[None] * _mean_over_triangles(emission_tex, uvs)
            return TriMesh(pos, nrm, uvs, per_tri, tan)

        return load

    # ------------------------------------------------------------------ lights
    def light(self, index, m: np.ndarray, node: int) -> None:
        """KHR_lights_punctual: intensity in candela (point, spot) or lux (directional) is taken as
        radiant intensity (W/sr) or irradiance (W/m^2) as it stands, as Khronos's sample viewer
        renders it (docs/guide/gltf.md#lights)."""
        lights = ((self.gltf.extensions or {}).get("KHR_lights_punctual") or {}).get("lights", [])
        if index is None or not 0 <= index < len(lights):
            raise SceneError(f"node {node}: KHR_lights_punctual light {index} does not exist", self.path)
        lt = lights[index]
        kind = lt.get("type")
        color = np.array(lt.get("color", [1.0, 1.0, 1.0]), float) * float(lt.get("intensity", 1.0))
        if np.any(color < 0) or not np.all(np.isfinite(color)):
            raise SceneError(f"light {index}: color and intensity must be finite and non-negative", self.path)
        if lt.get("range") is not None:
            warn(f"light {index}: 'range' is not applied (the light falls off with the inverse square, without the "
                 "cutoff)", self.path)
        pos = m[:3, 3].copy()
        axis = -m[:3, 2]
        if np.linalg.norm(axis) <= 0:
            raise SceneError(f"light {index}: its node's transform has no direction", self.path)
        axis = axis / np.linalg.norm(axis)
        if kind == "point":
            self.emitters.append({"type": "point", "position": pos, "intensity": color, "_loc": self.path})
        elif kind == "directional":
            self.emitters.append({"type": "directional", "direction": axis, "irradiance": color, "_loc": self.path})
        elif kind == "spot":
            spot = lt.get("spot", {})
            inner = float(spot.get("innerConeAngle", 0.0))
            outer = float(spot.get("outerConeAngle", math.pi / 4))
            if not 0 <= inner < outer <= math.pi / 2:
                raise SceneError(f"light {index}: the spot needs 0 <= innerConeAngle < outerConeAngle <= pi/2",
                                 self.path)
            self.emitters.append({"type": "spot", "to_world": frame_along(axis, pos), "intensity": color,
                                  "cutoff_angle": math.degrees(outer), "beam_width": math.degrees(inner),
                                  "falloff": "squared_ramp", "_loc": self.path})
        else:
            raise SceneError(f"light {index}: unknown type '{kind}'", self.path)

    # ------------------------------------------------------------------ camera
    def sensor(self) -> dict:
        cams = self.gltf.cameras or []
        chosen = None
        if self.camera_name is not None:
            named = [c for c in self.cameras if c[0] == self.camera_name]
            if not named:
                have = ", ".join(repr(c[0]) for c in self.cameras if c[0]) or "none named"
                raise SceneError(f"no camera node named '{self.camera_name}' (the file has: {have})", self.path)
            chosen = named[0]
        elif self.cameras:
            chosen = self.cameras[0]
        if chosen is None:
            return self.default_sensor()
        name, ci, m, self.camera_node = chosen
        if not 0 <= ci < len(cams):
            raise SceneError(f"camera {ci} does not exist", self.path)
        cam = cams[ci]
        if cam.type != "perspective" or cam.perspective is None:
            raise SceneError(f"camera {ci}: '{cam.type}' cameras are not supported (perspective only)", self.path)
        yfov = cam.perspective.yfov
        aspect = cam.perspective.aspectRatio or 16.0 / 9.0
        if not (yfov and 0 < yfov < math.pi) or aspect <= 0:
            raise SceneError(f"camera {ci}: yfov must be in (0, pi) and aspectRatio positive", self.path)
        rot = m[:3, :3] / np.linalg.norm(m[:3, :3], axis=0, keepdims=True)
        to_world = np.eye(4)
        to_world[:3, :3] = rot @ np.diag([-1.0, 1.0, -1.0])
        to_world[:3, 3] = m[:3, 3]
        return self._sensor(to_world, math.degrees(yfov), aspect)

    def default_sensor(self) -> dict:
        """No camera: 45 degrees vertically, looking down -Z at the centre of the scene's bounding
        box from where the box's bounding sphere just fills the view (times 1.1), 16:9."""
        corners = []
        for acc, m, what in self.positions:
            p = self.buffers.accessor(acc, what)
            corners.append(np.stack([p.min(0), p.max(0)]) @ m[:3, :3].T + m[:3, 3])
        b = np.concatenate(corners)
        lo, hi = b.min(0), b.max(0)
        centre, radius = 0.5 * (lo + hi), max(0.5 * float(np.linalg.norm(hi - lo)), 1e-6)
        dist = 1.1 * radius / math.sin(DEFAULT_YFOV / 2)
        to_world = np.diag([-1.0, 1.0, -1.0, 1.0])
        to_world[:3, 3] = centre + np.array([0.0, 0.0, dist])
        warn("the file has no camera: the view is a default framing from +Z (docs/guide/gltf.md#cameras)", self.path)
        return self._sensor(to_world, math.degrees(DEFAULT_YFOV), 16.0 / 9.0)

    def _sensor(self, to_world, fov_y, aspect) -> dict:
        height = DEFAULT_HEIGHT
        width = max(1, int(round(height * aspect)))
        return {"type": "perspective", "fov": fov_y, "fov_axis": "y", "to_world": to_world, "_loc": self.path,
                "film": {"type": "hdrfilm", "width": width, "height": height, "rfilter": {"type": "box"}},
                "sampler": {"type": "independent", "sample_count": 16}}


def _mean_over_triangles(tex, uvs: np.ndarray) -> np.ndarray:
    """An emissive texture's mean over each triangle, from its value at the corners, the edge
    midpoints and the centroid (nearest texel, with the sampler's wrap)."""
    img, smp = tex
    h, w = img.shape[:2]
    bary = np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [.5, .5, 0], [0, .5, .5], [.5, 0, .5], [1 / 3, 1 / 3, 1 / 3]])
    pts = np.einsum("kc,tcd->tkd", bary, uvs)
    to_uv = smp["to_uv"]
    u = pts[..., 0] * to_uv[0, 0] + pts[..., 1] * to_uv[0, 1] + to_uv[0, 3]
    v = pts[..., 0] * to_uv[1, 0] + pts[..., 1] * to_uv[1, 1] + to_uv[1, 3]
    if smp["wrap_mode"] == "clamp":
        u, v = np.clip(u, 0, 1 - 1e-9), np.clip(v, 0, 1 - 1e-9)
    else:
        u, v = u - np.floor(u), v - np.floor(v)
    x = np.minimum((u * w).astype(int), w - 1)
    y = np.minimum((v * h).astype(int), h - 1)
    return img[y, x].mean(axis=1)

