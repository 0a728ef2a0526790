"""Stage "primary hits" (every method's first stage): one camera ray per pixel and sample.

Reads: scene, camera (the camera stream shared by every method, so methods compare with common
random numbers). Writes: gb (the G-buffer: triangle and barycentrics, and the camera position its
rays are rebuilt from, which `trace_primary_hits` sets before the launch), weight (the filter
weight of the camera sample), emission (emitted radiance seen directly, times the filter weight:
the depth-1 term of every estimator), events (one ray).
"""
import warp as wp

from ...device.camera import Camera, camera_ray
from ...device.intersect import T_MAX, trace_closest
from ...device.lights import env_eval, triangle_emission
from ...device.scene_device import SceneDevice
from ...device.types import ENV_NONE
from .events import EventCounts, packed_events, ray_events
from .gbuffer import GBuffer, set_camera_origin


@wp.kernel
def primary_hits_kernel(offset: int, scene: SceneDevice, camera: Camera, seed: wp.uint32, frame: wp.uint32,
                        sample: int, hide_emitters: int, gb: GBuffer, weight: wp.array(dtype=float),
                        emission: wp.array(dtype=wp.vec3), events: wp.array(dtype=EventCounts)):
    pixel = wp.tid() + offset
    ray = camera_ray(camera, seed, frame, pixel, sample)
    hit = trace_closest(scene, ray.o, ray.d, T_MAX)
    gb.tri[pixel] = hit.tri
    gb.bary[pixel] = hit.bary
    weight[pixel] = ray.weight
    Le = wp.vec3(0.0)
    if hide_emitters == 0:
        if hit.valid != 0:
            Le = triangle_emission(scene, hit.tri, hit.ns, -ray.d)
        elif scene.env_kind != ENV_NONE:
            Le = env_eval(scene, ray.d)
    emission[pixel] = Le * ray.weight
    events[pixel] = packed_events(ray_events(1))


def trace_primary_hits(integrator, camera, seed, frame, sample: int, hide_emitters: int, gb: GBuffer, weight,
                       emission) -> None:
    """The stage for one sample, timed as "gbuffer": gb takes the camera's position (the rays its
    readers rebuild start there), then the launch writes the hits."""
    set_camera_origin(gb, camera)
    integrator.run_stage("gbuffer", primary_hits_kernel,
                         [integrator.dscene.scene, camera, seed, frame, sample, hide_emitters], [gb, weight, emission])
