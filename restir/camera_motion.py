"""Scripted camera motion over frames, so that temporal reuse meets a moving camera.

`orbit`: the camera turns about the vertical axis (its own up vector) through the centre of the
scene's bounding box, `speed` degrees per frame. `dolly`: it moves along its view direction by
`speed` times the bounding-box diagonal per frame. `none`: a static camera. The scene may move as
well (scene/animation.py); the pivot and the diagonal are the rest pose's.
"""
import numpy as np

from .scene.transforms import rotate, translate

MOTIONS = ("none", "orbit", "dolly")


def camera_pose(to_world: np.ndarray, bounds: tuple[np.ndarray, np.ndarray], motion: str, speed: float,
                frame: int) -> np.ndarray:
    if motion == "none" or speed == 0.0:
        return to_world
    lo, hi = bounds
    if motion == "orbit":
        pivot = 0.5 * (lo + hi)
        up = to_world[:3, 1]
        return translate(pivot) @ rotate(up, speed * frame) @ translate(-pivot) @ to_world
    if motion == "dolly":
        return translate(to_world[:3, 2] * (speed * frame * float(np.linalg.norm(hi - lo)))) @ to_world
    raise ValueError(f"unknown camera motion '{motion}'")
