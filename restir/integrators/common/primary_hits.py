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
error a denoiser leaves on a lit Cornell box (docs/guide/when_restir_pays.md#the-emission-rays).
With `emission.adaptive` (the default) the n rays are traced only at pixels where recent launches
saw the emission vary nearby or a small emitter lies near, one elsewhere (common/emission_edges.py:
why that stays unbiased); the stage then also reads and writes those records.
"""
import functools

import warp as wp

from ...device.camera import Camera, camera_u, generate_ray, lattice_u, lens_u
from ...device.intersect import T_MAX, SurfaceHit, trace_closest
from ...device.lights import env_eval, triangle_emission
from ...device.scene_device import SceneDevice
from ...device.types import ENV_NONE
from .emission_edges import edge_choice, edge_launch, edge_record, emission_rays, emission_sum, seen
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


@wp.struct
class LatticeEmission:
    Le: wp.vec3     # rays 1..n-1: the sum of their emission seen directly times their filter weights
    record: float   # what every ray of the pixel saw, for the next launch (emission_edges.seen)


@wp.func
def lattice_emission(scene: SceneDevice, camera: Camera, pixel: int, u: wp.vec2, u_lens: wp.vec2, n: int,
                     first: float) -> LatticeEmission:
    """Rays 1..n-1 of `emission.rays` (ray 0 is the sample's own, at u, whose record is `first`).
    A thin lens's rays share the sample's aperture point u_lens: each ray's image position is
    still uniform, and so each ray's emission an unbiased estimate."""
    out = LatticeEmission()
    out.Le = wp.vec3(0.0)
    out.record = first
    for j in range(1, n):
        ray = generate_ray(camera, pixel % camera.width, pixel // camera.width, lattice_u(u, j, n), u_lens)
        Le = emission_seen(scene, trace_closest(scene, ray.o, ray.d, T_MAX), ray.d)
        out.Le += Le * ray.weight
        out.record = seen(out.record, Le)
    return out


MUTATIONS = ("emission_lattice_fixed", "emission_rays_by_own_ray")


def make_primary_hits_kernel(mutation: str = "none"):
    """The stage's kernel, or a build with one of ReSTIR PT's debug.mutation faults, its own
    module (the shipped kernel is built with none):
    - emission_lattice_fixed: rays 1..n-1 at the lattice's points unshifted by the sample's
      position, so they always sample the same spots of the pixel (biased at an emitter's edge);
    - emission_rays_by_own_ray: with emission.adaptive, the n rays traced where the sample's own
      ray saw emission rather than where the previous launch saw it vary (a choice that depends on
      the estimate it scales: biased low at an emitter's edge)."""
    fixed_lattice = mutation == "emission_lattice_fixed"
    by_own_ray = mutation == "emission_rays_by_own_ray"

    @wp.kernel(module=None if mutation == "none" else f"primary_hits_{mutation}")
    def primary_hits_kernel(offset: int, scene: SceneDevice, camera: Camera, seed: wp.uint32, frame: wp.uint32,
                            sample: int, hide_emitters: int, emission_rays: int, adaptive: int,
                            edges_previous: wp.array(dtype=wp.vec2), edge_marks: wp.array(dtype=wp.uint8),
                            gb: GBuffer, weight: wp.array(dtype=float),
                            emission: wp.array(dtype=wp.vec3), edges_current: wp.array(dtype=wp.vec2),
                            events: wp.array(dtype=EventCounts)):
        pixel = wp.tid() + offset
        u = camera_u(seed, frame, pixel, sample)
        u_lens = lens_u(seed, frame, pixel, sample)
        ray = generate_ray(camera, pixel % camera.width, pixel // camera.width, u, u_lens)
        hit = trace_closest(scene, ray.o, ray.d, T_MAX)
        gb.tri[pixel] = hit.tri
        gb.bary[pixel] = hit.bary
        if gb.from_camera == 0:  # rays from a thin lens start at different points: kept (gbuffer.py)
            gb.t[pixel] = hit.t
            gb.dir[pixel] = ray.d
        weight[pixel] = ray.weight
        Le = wp.vec3(0.0)
        rays = int(1)
        if hide_emitters == 0:
            Le0 = emission_seen(scene, hit, ray.d)
            Le = Le0 * ray.weight
            choice = edge_choice(edges_previous, edge_marks, camera, pixel, emission_rays, adaptive)
            n = choice.rays
            if wp.static(by_own_ray):
                n = wp.where(emission_sum(Le0) > 0.0, emission_rays, 1)
            record = emission_sum(Le0)
            if n > 1:
                shift = u
                if wp.static(fixed_lattice):
                    shift = wp.vec2(0.0)
                extra = lattice_emission(scene, camera, pixel, shift, u_lens, n, record)
                Le = (Le + extra.Le) / float(n)
                record = extra.record
                rays = n
            if emission_rays > 1 and adaptive != 0:
                edges_current[pixel] = edge_record(choice, record)
        emission[pixel] = Le
        events[pixel] = packed_events(ray_events(rays))

    return primary_hits_kernel


primary_hits_kernel = make_primary_hits_kernel()


@functools.cache
def mutant_kernel(mutation: str):
    """A mutation's build of the stage's kernel, made on first use."""
    return make_primary_hits_kernel(mutation)


def trace_primary_hits(integrator, camera, seed, frame, sample: int, hide_emitters: int, gb: GBuffer, weight,
                       emission, kernel=None) -> None:
    """The stage for one sample, timed as "gbuffer": gb takes the camera's position (the rays its
    readers rebuild start there), then the launch writes the hits (kernel: a mutation's build),
    and with emission.adaptive the records of where the emission varied (edge_launch)."""
    set_camera_origin(gb, camera)
    with edge_launch(integrator, "gbuffer", camera) as e:
        integrator.run_stage("gbuffer", kernel or primary_hits_kernel,
                             [integrator.dscene.scene, camera, seed, frame, sample, hide_emitters,
                              emission_rays(integrator), e.adaptive, e.previous, e.marks],
                             [gb, weight, emission, e.current], new_call=e.new_call)
