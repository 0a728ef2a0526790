"""Stage 1, G-buffer: one primary hit per pixel and its directly visible emission.

Reads: scene, camera (the camera stream shared by every method). Writes: gb_tri, gb_bary, gb_t
(hit: rebuilt by surface_at), gb_dir (primary ray direction), gb_weight (filter weight),
emission (emitted radiance seen directly, times the filter weight; the depth-1 term of
max_depth 2), events (one ray).
"""
import warp as wp

from ...device.camera import Camera, camera_ray
from ...device.intersect import T_MAX, trace_closest
from ...device.lights import env_eval, triangle_emission
from ...device.scene_device import SceneDevice
from ...device.types import ENV_NONE
from .params import DIParams


@wp.kernel
def gbuffer_kernel(offset: int, scene: SceneDevice, camera: Camera, params: DIParams,
                   gb_tri: wp.array(dtype=wp.int32), gb_bary: wp.array(dtype=wp.vec2), gb_t: wp.array(dtype=float),
                   gb_dir: wp.array(dtype=wp.vec3), gb_weight: wp.array(dtype=float), emission: wp.array(dtype=wp.vec3),
                   events: wp.array(dtype=wp.vec4i)):
    pixel = wp.tid() + offset
    ray = camera_ray(camera, params.seed, params.frame, pixel, params.sample)
    hit = trace_closest(scene, ray.o, ray.d, T_MAX)
    gb_dir[pixel] = ray.d
    gb_weight[pixel] = ray.weight
    gb_tri[pixel] = hit.tri
    gb_bary[pixel] = hit.bary
    gb_t[pixel] = hit.t
    Le = wp.vec3(0.0)
    if params.hide_emitters == 0:
        if hit.valid != 0:
            Le = triangle_emission(scene, hit.tri, hit.ns, -ray.d)
        elif scene.env_kind != ENV_NONE:
            Le = env_eval(scene, ray.d)
    emission[pixel] = Le * ray.weight
    events[pixel] = wp.vec4i(0, 0, 0, 1)
