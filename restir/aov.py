"""Arbitrary output variables for denoisers (`restir render --aov albedo,normal`), as Mitsuba's
`aov` integrator writes them: extra layers of the EXR beside the radiance.

- albedo: the reflectance at the first hit, the way denoisers (Intel Open Image Denoise) want it:
  the diffuse reflectance of diffuse and plastic surfaces (textures resolved), the specular
  reflectance of conductors, the specular transmittance of dielectrics; 0 where the ray escapes.
- normal: the world-space shading normal at the first hit (Mitsuba's `sh_normal`); 0 on a miss.

Both are filter-weighted averages over the render's first camera samples (one per frame, up to
AOV_SAMPLES frames), drawn from the camera stream every method shares: the same sub-pixel
positions as the radiance.
"""
import numpy as np
import warp as wp

from .config import AOVS
from .device.camera import Camera, camera_ray
from .device.intersect import T_MAX, trace_closest
from .device.scene_device import SceneDevice, textured_material
from .device.types import MAT_CONDUCTOR, MAT_DIELECTRIC, MAT_ROUGHCONDUCTOR, MAT_ROUGHDIELECTRIC, MAT_THINDIELECTRIC

AOV_SAMPLES = 64
CHANNELS = {"albedo": ("R", "G", "B"), "normal": ("X", "Y", "Z")}


@wp.kernel
def aov_kernel(offset: int, scene: SceneDevice, camera: Camera, seed: wp.uint32, samples: int,
               albedo: wp.array(dtype=wp.vec3), normal: wp.array(dtype=wp.vec3)):
    pixel = wp.tid() + offset
    a = wp.vec3(0.0)
    n = wp.vec3(0.0)
    wsum = float(0.0)
    for k in range(samples):
        ray = camera_ray(camera, seed, wp.uint32(k), pixel, 0)
        wsum += ray.weight
        hit = trace_closest(scene, ray.o, ray.d, T_MAX)
        if hit.valid != 0:
            m = textured_material(scene, hit.tri, hit.uv)
            r = m.reflectance
            if m.kind == MAT_CONDUCTOR or m.kind == MAT_ROUGHCONDUCTOR:
                r = m.specular_reflectance
            elif m.kind == MAT_DIELECTRIC or m.kind == MAT_THINDIELECTRIC or m.kind == MAT_ROUGHDIELECTRIC:
                r = m.specular_transmittance
            a += ray.weight * r
            n += ray.weight * hit.ns
    if wsum != 0.0:
        a = a / wsum
        n = n / wsum
    albedo[pixel] = a
    normal[pixel] = n


def compute_aovs(integrator, names, frames: int) -> dict:
    """{name: (H, W, 3) float32} for the integrator's scene and camera (frame 0's pose; an
    animated scene too is set to its frame 0, so that geometry and camera agree)."""
    from .parallel import launch_pixels

    integrator.dscene.set_frame(0)
    n = integrator.num_pixels
    out = {k: wp.zeros(n, dtype=wp.vec3, device=integrator.device) for k in AOVS}
    samples = max(1, min(AOV_SAMPLES, frames))  # frames: the camera samples to average (one per frame)
    launch_pixels(aov_kernel, n, [integrator.dscene.scene, integrator.camera(0), wp.uint32(integrator.settings.seed),
                                  samples], [out["albedo"], out["normal"]], integrator.device, integrator.slices)
    h, w = integrator.height, integrator.width
    return {k: out[k].numpy().reshape(h, w, 3).astype(np.float32) for k in names}
