"""Stage "primary hits" (every method's first stage): one camera ray per pixel and sample.

Reads: scene, camera (the camera stream shared by every method, so methods compare with common
random numbers). Writes: gb (the G-buffer: triangle and barycentrics, and the camera position its
rays are rebuilt from, which `trace_primary_hits` sets before the launch), weight (the filter
weight of the camera sample), emission (emitted radiance seen directly, times the filter weight:
the depth-1 term of every estimator), events (one ray, or `emission.rays`).

With the setting `emission.rays` = n > 1 the emission seen directly is the mean over n camera
rays: the sample's own and n - 1 more on a lattice shifted by its position (camera.lattice_u).
The rest of every path still starts at the sample's own hit. Each ray's emission is an unbiased
estimate of the pixel's, so the mean is; it spends n - 1 rays on the one term that path reuse
cannot improve: the edge of an emitter seen directly, sampled by one ray a pixel, is the largest
error a denoiser leaves on a lit Cornell box (BENCHMARKS.md, "The glossy box after the denoiser").
"""
import functools

import warp as wp

from ...device.camera import Camera, camera_u, generate_ray, lattice_u
from ...device.intersect import T_MAX, SurfaceHit, trace_closest
from ...device.lights import env_eval, triangle_emission
from ...device.scene_device import SceneDevice
from ...device.types import ENV_NONE
from .events import EventCounts, packed_events, ray_events
from .gbuffer import GBuffer, set_camera_origin


@wp.func
def emission_seen(scene: SceneDevice, hit: SurfaceHit, d: wp.vec3) -> wp.vec3:
    """The radiance emitted toward the camera by what a camera ray of direction d hits (the
    environment where it escapes)."""
    Le = wp.vec3(0.0)
    if hit.valid != 0:
        Le = triangle_emission(scene, hit.tri, hit.ns, -d)
    elif scene.env_kind != ENV_NONE:
        Le = env_eval(scene, d)
    return Le


@wp.func
def lattice_emission(scene: SceneDevice, camera: Camera, pixel: int, u: wp.vec2, n: int) -> wp.vec3:
    """Rays 1..n-1 of `emission.rays` (ray 0 is the sample's own, at u): the sum of their
    emission seen directly times their filter weights."""
    Le = wp.vec3(0.0)
    for j in range(1, n):
        ray = generate_ray(camera, pixel % camera.width, pixel // camera.width, lattice_u(u, j, n))
        Le += emission_seen(scene, trace_closest(scene, ray.o, ray.d, T_MAX), ray.d) * ray.weight
    return Le


def make_primary_hits_kernel(fixed_lattice: bool = False):
    """The stage's kernel. fixed_lattice builds the mutation `emission_lattice_fixed` (ReSTIR PT's
    debug.mutation): rays 1..n-1 of emission.rays at the lattice's points unshifted by the
    sample's position, so they always sample the same spots of the pixel (biased at an emitter's
    edge); the shipped kernel is built without it."""

    @wp.kernel(module="primary_hits_fixed_lattice" if fixed_lattice else None)
    def primary_hits_kernel(offset: int, scene: SceneDevice, camera: Camera, seed: wp.uint32, frame: wp.uint32,
                            sample: int, hide_emitters: int, emission_rays: int, gb: GBuffer,
                            weight: wp.array(dtype=float), emission: wp.array(dtype=wp.vec3),
                            events: wp.array(dtype=EventCounts)):
        pixel = wp.tid() + offset
        u = camera_u(seed, frame, pixel, sample)
        ray = generate_ray(camera, pixel % camera.width, pixel // camera.width, u)
        hit = trace_closest(scene, ray.o, ray.d, T_MAX)
        gb.tri[pixel] = hit.tri
        gb.bary[pixel] = hit.bary
        weight[pixel] = ray.weight
        Le = wp.vec3(0.0)
        rays = int(1)
        if hide_emitters == 0:
            Le = emission_seen(scene, hit, ray.d) * ray.weight
            if emission_rays > 1:
                shift = u
                if wp.static(fixed_lattice):
                    shift = wp.vec2(0.0)
                Le = (Le + lattice_emission(scene, camera, pixel, shift, emission_rays)) / float(emission_rays)
                rays = emission_rays
        emission[pixel] = Le
        events[pixel] = packed_events(ray_events(rays))

    return primary_hits_kernel


primary_hits_kernel = make_primary_hits_kernel()


@functools.cache
def fixed_lattice_kernel():
    """The mutation's kernel, built on first use."""
    return make_primary_hits_kernel(fixed_lattice=True)


def emission_rays(integrator) -> int:
    """The camera rays a sample traces for the emission seen directly: the `emission.rays`
    setting, or 1 with pixel-centre rays (RenderConfig.jitter off), where every ray would be the
    sample's own."""
    return int(integrator.settings.emission_rays) if integrator.dscene.jitter else 1


def trace_primary_hits(integrator, camera, seed, frame, sample: int, hide_emitters: int, gb: GBuffer, weight,
                       emission, kernel=None) -> None:
    """The stage for one sample, timed as "gbuffer": gb takes the camera's position (the rays its
    readers rebuild start there), then the launch writes the hits (kernel: a mutation's build)."""
    set_camera_origin(gb, camera)
    integrator.run_stage("gbuffer", kernel or primary_hits_kernel,
                         [integrator.dscene.scene, camera, seed, frame, sample, hide_emitters,
                          emission_rays(integrator)], [gb, weight, emission])
