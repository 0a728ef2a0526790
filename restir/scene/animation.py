"""Animated scenes: rigid motion of named objects and changing emitters, frame by frame.

A scene as loaded is its rest pose. An `Animation` says, for every frame, where each animated
object is (a 4x4 transform applied to its rest-pose geometry, in world space) and a factor on
its emission (0: switched off). An object is a shape (its triangles) or a point, spot or
directional light, named as the scene names it: a Mitsuba shape's `id` (or its key in a dict
scene), a builtin's part names, a glTF node's name.

Two ways to describe the motion:

- keyframes, per object (`Motion`): translation, rotation (unit quaternions, x y z w), scale
  and an emission factor over frame numbers, with glTF's interpolations (step, linear with
  spherical interpolation of rotations, cubic spline with in and out tangents), about a pivot;
- a callback `fn(frame) -> {name: {"to_world": 4x4, "emission": factor}}`, for motion computed
  in Python (either key may be left out: the rest pose, or the full emission).

`posed_scene(scene, frame)` gives the frame's geometry and lights; scene/upload.py puts them on the
device, keeping the previous frame's for the passes that read it (docs/guide/animation.md).
Frames are the time unit: frame f is the scene at time f, the same for every sample of the frame.
"""
from __future__ import annotations

import copy
import dataclasses
from dataclasses import dataclass, field

import numpy as np

from .errors import SceneError
from .transforms import transform_normals, transform_points

INTERPOLATIONS = ("step", "linear", "cubicspline")


@dataclass
class Keyframes:
    """Values over frames: `times` (K frame numbers, increasing) and `values` ((K, n); for
    "cubicspline" (K, 3, n): in-tangent, value, out-tangent per key, as glTF stores them).
    Before the first key the first value holds, after the last the last one."""
    times: np.ndarray
    values: np.ndarray
    interpolation: str = "linear"
    quaternion: bool = False  # values are unit quaternions (x, y, z, w): slerp, renormalized cubic

    def __post_init__(self):
        self.times = np.asarray(self.times, np.float64).reshape(-1)
        v = np.asarray(self.values, np.float64)
        if self.interpolation not in INTERPOLATIONS:
            raise SceneError(f"keyframe interpolation must be one of {', '.join(INTERPOLATIONS)}, "
                             f"not '{self.interpolation}'")
        k = len(self.times)
        if k == 0:
            raise SceneError("keyframes need at least one key")
        if not np.all(np.isfinite(self.times)) or np.any(np.diff(self.times) <= 0):
            raise SceneError("keyframe times must be finite and strictly increasing")
        if v.ndim == 1:
            v = v.reshape(k, -1) if self.interpolation != "cubicspline" else v.reshape(k, 3, -1)
        if self.interpolation == "cubicspline" and (v.ndim != 3 or v.shape[:2] != (k, 3)):
            raise SceneError(f"cubic-spline keyframes need (keys, 3, n) values (in-tangent, value, out-tangent), "
                             f"got {v.shape}")
        if self.interpolation != "cubicspline" and (v.ndim != 2 or v.shape[0] != k):
            raise SceneError(f"{k} keyframe times but values of shape {v.shape}")
        if not np.all(np.isfinite(v)):
            raise SceneError("keyframe values must be finite")
        self.values = v

    def _value(self, i: int) -> np.ndarray:
        return self.values[i, 1] if self.interpolation == "cubicspline" else self.values[i]

    def at(self, t: float) -> np.ndarray:
        times = self.times
        if t <= times[0]:
            return self._value(0).copy()
        if t >= times[-1]:
            return self._value(len(times) - 1).copy()
        i = int(np.searchsorted(times, t, side="right")) - 1
        t0, t1 = times[i], times[i + 1]
        s = (t - t0) / (t1 - t0)
        if self.interpolation == "step":
            return self._value(i).copy()
        if self.interpolation == "linear":
            a, b = self.values[i], self.values[i + 1]
            return slerp(a, b, s) if self.quaternion else (1.0 - s) * a + s * b
        # glTF 2.0, Appendix C: a cubic Hermite spline, tangents scaled by the key interval
        dt = t1 - t0
        v0, b0 = self.values[i, 1], self.values[i, 2]
        v1, a1 = self.values[i + 1, 1], self.values[i + 1, 0]
        s2, s3 = s * s, s * s * s
        out = ((2 * s3 - 3 * s2 + 1) * v0 + dt * (s3 - 2 * s2 + s) * b0 + (-2 * s3 + 3 * s2) * v1
               + dt * (s3 - s2) * a1)
        if self.quaternion:
            out = out / max(np.linalg.norm(out), 1e-30)
        return out


def slerp(a: np.ndarray, b: np.ndarray, s: float) -> np.ndarray:
    """Spherical interpolation of unit quaternions along the shorter arc."""
    a = a / np.linalg.norm(a)
    b = b / np.linalg.norm(b)
    d = float(np.dot(a, b))
    if d < 0.0:
        b, d = -b, -d
    if d > 0.9995:  # nearly equal: the chord, renormalized
        q = a + s * (b - a)
        return q / np.linalg.norm(q)
    theta = np.arccos(d)
    return (np.sin((1 - s) * theta) * a + np.sin(s * theta) * b) / np.sin(theta)


def quaternion_matrix(q) -> np.ndarray:
    """The 3x3 rotation of a unit quaternion (x, y, z, w)."""
    x, y, z, w = np.asarray(q, np.float64) / np.linalg.norm(q)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


def _keys(k, n: int, quaternion: bool = False) -> Keyframes | None:
    """A Keyframes, or a (times, values[, interpolation]) tuple made into one."""
    if k is None or isinstance(k, Keyframes):
        return k
    if isinstance(k, (tuple, list)) and len(k) in (2, 3):
        kf = Keyframes(k[0], k[1], *(k[2:] or ("linear",)), quaternion=quaternion)
        if kf.values.shape[-1] != n:
            raise SceneError(f"keyframe values need {n} components, got {kf.values.shape[-1]}")
        return kf
    raise SceneError(f"keyframes must be a restir.Keyframes or (times, values[, interpolation]), not {type(k).__name__}")


@dataclass
class Motion:
    """One object's keyframed motion: at frame t its rest-pose geometry is scaled, then rotated
    about `pivot`, then translated: x -> pivot + translation + R (S (x - pivot)). `emission`
    multiplies its emission (an area emitter's radiance, a delta light's intensity; 0: off).
    Each is a Keyframes or (times, values[, interpolation]); None: unchanged."""
    translation: Keyframes | tuple | None = None
    rotation: Keyframes | tuple | None = None
    scale: Keyframes | tuple | None = None
    emission: Keyframes | tuple | None = None
    pivot: np.ndarray = field(default_factory=lambda: np.zeros(3))

    def __post_init__(self):
        self.translation = _keys(self.translation, 3)
        self.rotation = _keys(self.rotation, 4, quaternion=True)
        if self.rotation is not None:
            self.rotation.quaternion = True
        self.scale = _keys(self.scale, 3)
        self.emission = _keys(self.emission, 1)
        self.pivot = np.asarray(self.pivot, np.float64).reshape(3)

    def transform(self, t: float) -> np.ndarray | None:
        if self.translation is None and self.rotation is None and self.scale is None:
            return None
        m = np.eye(4)
        if self.scale is not None:
            m[:3, :3] = np.diag(self.scale.at(t))
        if self.rotation is not None:
            m[:3, :3] = quaternion_matrix(self.rotation.at(t)) @ m[:3, :3]
        offset = self.translation.at(t) if self.translation is not None else np.zeros(3)
        m[:3, 3] = self.pivot + offset - m[:3, :3] @ self.pivot
        return m

    def emission_at(self, t: float) -> float:
        return 1.0 if self.emission is None else float(self.emission.at(t)[0])


@dataclass
class Animation:
    """The motion of a scene's objects: `motions` ({name: Motion}) and/or `callback`
    (fn(frame) -> {name: {"to_world": 4x4, "emission": factor}}), the callback's entries applied
    after the keyframes'. `frames`: the length of the animation in frames, if it has one (the
    CLI's default frame count for an animated builtin)."""
    motions: dict = field(default_factory=dict)
    callback: object = None
    frames: int | None = None

    def state(self, frame: int) -> dict:
        """{name: (4x4 or None, emission factor)} at `frame`."""
        out = {name: (m.transform(frame), m.emission_at(frame)) for name, m in self.motions.items()}
        if self.callback is not None:
            got = self.callback(frame)
            if not isinstance(got, dict):
                raise SceneError(f"the animation callback returned {type(got).__name__} for frame {frame}, not a "
                                 "dict {name: {'to_world': 4x4, 'emission': factor}}")
            for name, entry in got.items():
                if not isinstance(entry, dict) or set(entry) - {"to_world", "emission"}:
                    raise SceneError(f"the animation callback's entry for '{name}' must be a dict with 'to_world' "
                                     "and/or 'emission'")
                m = entry.get("to_world")
                if m is not None:
                    m = np.asarray(m, np.float64)
                    if m.shape != (4, 4) or not np.all(np.isfinite(m)):
                        raise SceneError(f"frame {frame}: the to_world of '{name}' is not a finite 4x4 matrix")
                e = float(entry.get("emission", 1.0))
                if not np.isfinite(e) or e < 0:
                    raise SceneError(f"frame {frame}: the emission factor of '{name}' must be finite and >= 0")
                prev = out.get(name, (None, 1.0))
                out[name] = (m if m is not None else prev[0], e if "emission" in entry else prev[1])
        return out


def check_animation(scene, animation: Animation) -> None:
    """Refuse names the scene does not have and singular transforms, before any frame renders."""
    known = set(scene.objects) | set(scene.delta_light_names)
    unknown = sorted(set(animation.motions) - known)
    if unknown:
        raise SceneError(f"the animation moves {', '.join(repr(u) for u in unknown)}, which the scene does not have "
                         f"(its objects: {', '.join(sorted(known)) or 'none'})")
    for name, m in animation.motions.items():
        if not isinstance(m, Motion):
            raise SceneError(f"the motion of '{name}' must be a restir.Motion, not {type(m).__name__}")


def posed_scene(scene, frame: int):
    """The scene at `frame` (a copy sharing what does not move): each animated object's rest
    geometry under its transform, its emission times its factor; a delta light's position and axis
    moved and its intensity scaled. A static scene is returned as it is."""
    anim = scene.animation
    if anim is None:
        return scene
    pos, nrm, tan = scene.positions, scene.normals, scene.tangents
    emis = scene.tri_emission
    lights = list(scene.delta_lights)
    pos, nrm, emis = pos.copy(), nrm.copy(), emis.copy()
    tan = tan.copy() if tan is not None else None
    for name, (m, e) in anim.state(frame).items():
        if name in scene.objects:
            lo, hi = scene.objects[name]
            if m is not None:
                pos[lo:hi], nrm[lo:hi], t = posed_object(scene, name, m, frame)
                if tan is not None:
                    tan[lo:hi] = t
            emis[lo:hi] = scene.tri_emission[lo:hi] * e
        else:
            i = scene.delta_light_names[name]
            lights[i] = posed_delta_light(lights[i], m, e)
    out = copy.copy(scene)
    out.positions, out.normals = pos.astype(np.float32), nrm.astype(np.float32)
    out.tangents = tan.astype(np.float32) if tan is not None else None
    out.tri_emission, out.delta_lights = emis.astype(np.float32), lights
    return out


def posed_object(scene, name: str, m: np.ndarray, frame: int) -> tuple:
    """An object's rest triangles under transform m: (positions, normals, tangents or None), each
    (n, 3, k) float32; a singular or mirroring m refused."""
    det = np.linalg.det(m[:3, :3])
    if abs(det) <= 1e-12:
        raise SceneError(f"frame {frame}: the transform of '{name}' is singular")
    if det < 0:  # it would turn the triangles' winding, and with it which side emits
        raise SceneError(f"frame {frame}: the transform of '{name}' mirrors it (negative determinant)")
    lo, hi = scene.objects[name]
    pos = transform_points(m, scene.positions[lo:hi].reshape(-1, 3)).reshape(-1, 3, 3).astype(np.float32)
    nrm = transform_normals(m, scene.normals[lo:hi].reshape(-1, 3)).reshape(-1, 3, 3).astype(np.float32)
    tan = None
    if scene.tangents is not None:
        tan = scene.tangents[lo:hi].copy()
        t = tan[:, :, :3].reshape(-1, 3) @ m[:3, :3].T
        ln = np.linalg.norm(t, axis=1, keepdims=True)
        tan[:, :, :3] = (t / np.where(ln > 0, ln, 1.0)).reshape(-1, 3, 3)
        tan = tan.astype(np.float32)
    return pos, nrm, tan


def posed_delta_light(d, m, e: float):
    """A delta light (DeltaLightDesc) moved by m (None: where it is) and its intensity times e."""
    d = dataclasses.replace(d)
    if m is not None:
        d.position = transform_points(m, np.asarray(d.position, np.float64)[None])[0]
        axis = m[:3, :3] @ np.asarray(d.axis, np.float64)
        d.axis = axis / np.linalg.norm(axis)
    d.intensity = np.asarray(d.intensity, np.float64) * e
    return d


def moving_objects(scene, state: dict) -> set:
    """The objects with triangles that an animation state (Animation.state) gives a transform: what
    the ray tracer refits, the rest of the scene keeping its structure."""
    return {n for n, (m, _) in state.items() if m is not None and n in scene.objects}


def refuse_for_one_reference(scene, what: str) -> None:
    """A measurement against one reference image (compare, sweep) cannot judge an animated scene,
    whose every frame has its own expectation: refused rather than measured against the wrong image."""
    if scene.animation is not None:
        raise SceneError(f"the scene is animated, and {what} measures every frame against one reference image; a "
                         "moving scene needs a reference per frame, which it does not compute yet. restir validate "
                         "tests each frame of an animated scene on its own (docs/guide/animation.md)")


def check_picklable(scene) -> None:
    """An animated scene sent to worker processes needs an animation that pickles (keyframes, a
    glTF file's; a lambda or a local function does not)."""
    import pickle

    if scene.animation is None:
        return
    try:
        pickle.dumps(scene.animation)
    except Exception:
        raise SceneError("the scene's animation callback cannot be sent to worker processes (a lambda or a "
                         "local function does not pickle): use keyframes (restir.Motion), a module-level "
                         "function, or one worker") from None


def animate(scene, motions: dict | None = None, callback=None, frames: int | None = None):
    """`scene` (not changed) with an animation: a copy whose objects move as `motions`
    ({name: restir.Motion}) and/or `callback` (fn(frame) -> {name: {"to_world": 4x4,
    "emission": factor}}) say. The names are the scene's objects (`scene.objects`) and named
    delta lights (`scene.delta_light_names`)."""
    anim = Animation(dict(motions or {}), callback, frames)
    check_animation(scene, anim)
    out = copy.copy(scene)
    out.animation = anim
    posed_scene(out, 0)  # a callback's or a transform's error shows now, not in the middle of a render
    return out
