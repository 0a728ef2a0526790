"""4x4 affine transforms as Mitsuba composes them (each new operation applied on the left)."""
import numpy as np


def translate(v) -> np.ndarray:
    m = np.eye(4)
    m[:3, 3] = v
    return m


def scale(v) -> np.ndarray:
    return np.diag([v[0], v[1], v[2], 1.0])


def rotate(axis, angle_deg: float) -> np.ndarray:
    a = np.asarray(axis, float)
    n = np.linalg.norm(a)
    if n == 0:
        raise ValueError("rotation axis is zero")
    x, y, z = a / n
    t = np.radians(angle_deg)
    c, s = np.cos(t), np.sin(t)
    C = 1 - c
    m = np.eye(4)
    m[:3, :3] = [
        [x * x * C + c, x * y * C - z * s, x * z * C + y * s],
        [y * x * C + z * s, y * y * C + c, y * z * C - x * s],
        [z * x * C - y * s, z * y * C + x * s, z * z * C + c],
    ]
    return m


def look_at(origin, target, up) -> np.ndarray:
    """Camera-to-world: local +z toward target, +y up, +x = up x dir ("left")."""
    o = np.asarray(origin, float)
    d = np.asarray(target, float) - o
    if np.linalg.norm(d) == 0:
        raise ValueError("lookat origin and target coincide")
    d /= np.linalg.norm(d)
    left = np.cross(np.asarray(up, float), d)
    if np.linalg.norm(left) == 0:
        raise ValueError("lookat up vector is parallel to the view direction")
    left /= np.linalg.norm(left)
    new_up = np.cross(d, left)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = left, new_up, d, o
    return m


def transform_points(m: np.ndarray, p: np.ndarray) -> np.ndarray:
    return p @ m[:3, :3].T + m[:3, 3]


def transform_normals(m: np.ndarray, n: np.ndarray) -> np.ndarray:
    inv_t = np.linalg.inv(m[:3, :3]).T
    out = n @ inv_t.T
    ln = np.linalg.norm(out, axis=-1, keepdims=True)
    return out / np.where(ln > 0, ln, 1)


def frame_along(z: np.ndarray, origin: np.ndarray) -> np.ndarray:
    """A rigid 4x4 transform whose local +z is the unit vector z and whose origin is `origin`
    (the x axis any perpendicular one): a spot's to_world from where it is and where it shines."""
    a = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(a, z)
    x /= np.linalg.norm(x)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = x, np.cross(z, x), z, origin
    return m
