"""The viewer's camera: the browser's pose (viser's, OpenCV's convention: the camera looks down
+Z with +Y down and +X right) and restir's (Mitsuba's: down +Z with +Y up and +X left), and the
view written out so that `restir render` reproduces it."""
import math

import numpy as np


def quaternion_matrix(wxyz) -> np.ndarray:
    """The rotation of a unit quaternion (w, x, y, z)."""
    w, x, y, z = np.asarray(wxyz, float) / np.linalg.norm(wxyz)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def to_world_from_browser(position, wxyz) -> np.ndarray:
    """restir's camera-to-world for the browser's camera at `position` turned by `wxyz`: the same
    view axis, its right and down axes negated into Mitsuba's left and up."""
    r = quaternion_matrix(wxyz)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2] = -r[:, 0], -r[:, 1], r[:, 2]
    m[:3, 3] = np.asarray(position, float)
    return m


def browser_view(to_world: np.ndarray, distance: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(position, look-at point `distance` ahead, up) of restir's camera, for the browser's orbit
    controls."""
    m = np.asarray(to_world, float)
    forward = m[:3, 2] / np.linalg.norm(m[:3, 2])
    up = m[:3, 1] / np.linalg.norm(m[:3, 1])
    position = m[:3, 3].copy()
    return position, position + distance * forward, up


def fov_axis_y(fov_deg: float, fov_axis: str, width: int, height: int) -> float:
    """The vertical field of view (degrees) of a camera whose `fov` spans `fov_axis`."""
    axis = fov_axis
    if axis == "smaller":
        axis = "x" if width <= height else "y"
    elif axis == "larger":
        axis = "x" if width >= height else "y"
    if axis == "y":
        return fov_deg
    if axis == "x":
        return math.degrees(2 * math.atan(math.tan(math.radians(fov_deg) / 2) * height / width))
    # the diagonal
    t = math.tan(math.radians(fov_deg) / 2) / math.hypot(width, height)
    return math.degrees(2 * math.atan(t * height))


def view_as_text(to_world: np.ndarray, fov_y_deg: float) -> tuple[str, str]:
    """The view as a Mitsuba `<sensor>` element (for an XML scene or a builtin's file) and as
    Python that sets it on a loaded scene, so that `restir render` or `restir.render` reproduce
    it."""
    m = np.asarray(to_world, float)
    origin, target, up = m[:3, 3], m[:3, 3] + m[:3, 2], m[:3, 1]

    def v(a):
        return ", ".join(f"{x:.6g}" for x in a)

    xml = (f'<sensor type="perspective">\n    <float name="fov" value="{fov_y_deg:.6g}"/>\n'
           f'    <string name="fov_axis" value="y"/>\n    <transform name="to_world">\n'
           f'        <lookat origin="{v(origin)}" target="{v(target)}" up="{v(up)}"/>\n    </transform>\n'
           f'    <!-- the scene\'s film, sampler and filter as they were -->\n</sensor>')
    py = (f"from restir.scene.transforms import look_at\n"
          f"scene.camera.to_world = look_at([{v(origin)}], [{v(target)}], [{v(up)}])\n"
          f"scene.camera.fov, scene.camera.fov_axis = {fov_y_deg:.6g}, \"y\"")
    return xml, py

