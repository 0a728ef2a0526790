"""Small scene dicts and device-scene helpers for tests."""
import numpy as np
import warp as wp

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
