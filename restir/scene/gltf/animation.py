"""glTF 2.0 animations as restir's (docs/guide/gltf.md#animations): the channels that move nodes
(translation, rotation, scale, with their samplers' step, linear or cubic-spline interpolation)
animate the meshes and lights under those nodes, rigidly.

Every animation of the file plays at once, from time 0; frame f is at time f / fps seconds.
An object's transform at a frame is its node's world matrix then, times the inverse of its world
matrix as loaded (the rest pose, the nodes' own translation, rotation and scale), applied to its
rest geometry in world space. Morph-target weights are not played (a warning); a channel on a node
that has a `matrix` is refused, as the specification forbids it.
"""
import numpy as np

from ..animation import Animation, Keyframes, quaternion_matrix
from ..errors import SceneError, warn

PATHS = {"translation": 3, "rotation": 4, "scale": 3}
DEFAULT_FPS = 30.0


class NodeMotion:
    """A callable animation (scene/animation.py's callback form) that pickles: the node tree's
    rest transforms and parents, the channels' keyframes over frames, and which node carries each
    object."""

    def __init__(self, parents: list, rest: list, channels: dict, objects: dict):
        self.parents = parents      # per node, its parent's index or -1
        self.rest = rest            # per node, (translation, quaternion, scale) or a 4x4 matrix
        self.channels = channels    # {(node, path): Keyframes over frames}
        self.objects = objects      # {object name: node}
        self._rest_world = {n: self._world(n, None) for n in set(objects.values())}

    def _local(self, n: int, frame) -> np.ndarray:
        r = self.rest[n]
        if isinstance(r, np.ndarray):
            return r
        t, q, s = r
        if frame is not None:
            t = self.channels[(n, "translation")].at(frame) if (n, "translation") in self.channels else t
            q = self.channels[(n, "rotation")].at(frame) if (n, "rotation") in self.channels else q
            s = self.channels[(n, "scale")].at(frame) if (n, "scale") in self.channels else s
        m = np.eye(4)
        m[:3, :3] = quaternion_matrix(q) @ np.diag(s)
        m[:3, 3] = t
        return m

    def _world(self, n: int, frame) -> np.ndarray:
        m = np.eye(4)
        while n >= 0:
            m = self._local(n, frame) @ m
            n = self.parents[n]
        return m

    def __call__(self, frame: int) -> dict:
        out, cache = {}, {}
        for name, n in self.objects.items():
            if n not in cache:
                cache[n] = self._world(n, frame) @ np.linalg.inv(self._rest_world[n])
            out[name] = {"to_world": cache[n]}
        return out


def rest_transform(node):
    """A node's own transform as the animation reads it: (t, q, s), or its `matrix`."""
    if node.matrix is not None and len(node.matrix) == 16:
        return np.array(node.matrix, float).reshape(4, 4).T
    t = np.array(node.translation if node.translation is not None else [0, 0, 0], float)
    q = np.array(node.rotation if node.rotation is not None else [0, 0, 0, 1], float)
    s = np.array(node.scale if node.scale is not None else [1, 1, 1], float)
    return t, q, s


def read_animations(gltf, buffers, parents: list, objects: dict, fps: float, path: str,
                    camera_node: int | None = None) -> Animation | None:
    """The file's animations as an Animation over the objects ({name: node}) that move, or None
    where nothing that renders moves. A warning when the camera's node (camera_node) moves: restir's
    camera follows its own motion settings, not the file's."""
    if not gltf.animations:
        return None
    if not (np.isfinite(fps) and fps > 0):
        raise SceneError(f"fps must be a positive number, not {fps}", path)
    nodes = gltf.nodes or []
    channels = {}
    end = 0.0
    for ai, anim in enumerate(gltf.animations):
        samplers = anim.samplers or []
        for ci, ch in enumerate(anim.channels or []):
            what = f"animation {ai} channel {ci}"
            target = ch.target
            if target is None or target.node is None:
                continue  # a channel without a node targets an extension's property: nothing here reads it
            n, prop = target.node, target.path
            if not 0 <= n < len(nodes):
                raise SceneError(f"{what}: node {n} does not exist", path)
            if prop == "weights":
                warn(f"{what}: morph-target weights are not played", path)
                continue
            if prop not in PATHS:
                raise SceneError(f"{what}: unknown target path '{prop}'", path)
            if nodes[n].matrix is not None and len(nodes[n].matrix) == 16:
                raise SceneError(f"{what}: node {n} has a matrix, and glTF allows no animation of such a node", path)
            if ch.sampler is None or not 0 <= ch.sampler < len(samplers):
                raise SceneError(f"{what}: sampler {ch.sampler} does not exist", path)
            smp = samplers[ch.sampler]
            interp = {"STEP": "step", "LINEAR": "linear", "CUBICSPLINE": "cubicspline"}.get(smp.interpolation or "LINEAR")
            if interp is None:
                raise SceneError(f"{what}: unknown interpolation '{smp.interpolation}'", path)
            times = np.asarray(buffers.accessor(smp.input, f"{what} input"), float).reshape(-1)
            values = np.asarray(buffers.accessor(smp.output, f"{what} output"), float)
            k, width = len(times), PATHS[prop]
            values = values.reshape(k, 3, width) if interp == "cubicspline" else values.reshape(k, width)
            if interp == "cubicspline":  # tangents are per second; Keyframes' times are frames
                values = values * np.array([1.0 / fps, 1.0, 1.0 / fps])[None, :, None]
            try:
                keys = Keyframes(times * fps, values, interp, quaternion=prop == "rotation")
            except SceneError as e:
                raise SceneError(f"{what}: {e.args[0] if e.args else e}", path) from None
            if (n, prop) in channels:
                warn(f"{what}: node {n}'s {prop} is animated twice; the later channel plays", path)
            channels[(n, prop)] = keys
            end = max(end, float(times[-1]))
    if not channels:
        return None
    animated = {n for n, _ in channels}

    def moves(n: int) -> bool:
        while n >= 0:
            if n in animated:
                return True
            n = parents[n]
        return False

    if camera_node is not None and moves(camera_node):
        warn("the camera's animation is not played: the camera stays where its node stands at time 0", path)

    moving = {name: n for name, n in objects.items() if moves(n)}
    if not moving:
        return None
    rest = [rest_transform(nd) for nd in nodes]
    return Animation(callback=NodeMotion(parents, rest, channels, moving), frames=int(np.ceil(end * fps)) + 1)
