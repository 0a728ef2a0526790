"""The primary-hit G-buffer keeps a hit (triangle, barycentrics) and the camera position, and
load_shading rebuilds the ray from them (common/gbuffer.py). Checked against the camera rays
themselves, traced again: for the history G-buffer of a moving camera too, whose rays start where
the camera was a frame earlier."""
import numpy as np
import warp as wp

import restir
from restir.api import make_integrator
from restir.device.camera import Camera, camera_ray
from restir.device.intersect import T_MAX, trace_closest
from restir.device.sampling import to_world
from restir.device.scene_device import SceneDevice
from restir.integrators.common.gbuffer import GBuffer
from restir.integrators.common.shading import load_shading


@wp.kernel
def ray_errors_kernel(scene: SceneDevice, camera: Camera, seed: wp.uint32, frame: wp.uint32, gb: GBuffer,
                      out: wp.array(dtype=wp.vec3)):
    """Per pixel: (1 when the hit and the rebuilt shading agree on validity, the relative
    distance error, 1 - cos(angle) between the traced and the rebuilt direction)."""
    pixel = wp.tid()
    ray = camera_ray(camera, seed, frame, pixel, 0)
    hit = trace_closest(scene, ray.o, ray.d, T_MAX)
    s = load_shading(scene, gb, pixel)
    out[pixel] = wp.vec3(0.0, 0.0, 0.0)
    if (hit.valid != 0) != (s.valid != 0):
        return
    if hit.valid == 0:
        out[pixel] = wp.vec3(1.0, 0.0, 0.0)
        return
    # s.wi is the direction to the camera in the shading frame: back to world
    wi = to_world(s.frame, s.wi)
    out[pixel] = wp.vec3(1.0, wp.abs(s.hit.t - hit.t) / hit.t, 1.0 - wp.dot(-ray.d, wi))


def test_primary_rays_are_rebuilt_from_the_camera_position():
    scene = restir.load_scene("builtin:cornell-box-glossy", width=48, height=48)
    integ = make_integrator(scene, restir.RenderConfig(method="restir-pt", spp=1, max_depth=3, seed=5,
                                                       camera_motion="orbit"))
    assert integ.gbuffers.current.from_camera == 1
    for frame in (0, 1, 2):
        integ.render_frame(frame)
    # after frame 2 the history holds frame 2's hits; the other G-buffer frame 1's
    for gb, frame in ((integ.gbuffers.previous, 2), (integ.gbuffers.current, 1)):
        out = wp.zeros(integ.num_pixels, dtype=wp.vec3, device=integ.device)
        wp.launch(ray_errors_kernel, dim=integ.num_pixels, device=integ.device,
                  inputs=[integ.dscene.scene, integ.camera(frame), wp.uint32(5), wp.uint32(frame), gb, out])
        e = out.numpy()
        assert (e[:, 0] == 1.0).all(), f"frame {frame}: hit validity differs at {np.flatnonzero(e[:, 0] != 1)}"
        assert e[:, 1].max() < 1e-5 and e[:, 2].max() < 1e-6, (frame, e[:, 1].max(), e[:, 2].max())
    # the camera moved: the two G-buffers' origins differ (so the history's was not the current's)
    a, b = np.array(integ.gbuffers.previous.origin), np.array(integ.gbuffers.current.origin)
    assert np.linalg.norm(a - b) > 1e-3


def test_only_stored_rays_hold_per_pixel_rays():
    """32 B a pixel less than a G-buffer with its rays: the primary-hit ones keep 12 B."""
    scene = restir.load_scene("builtin:cornell-box", width=8, height=8)
    res = restir.render(scene, restir.RenderConfig(method="suffix-restir", spp=1))
    bpp = res.stats["bytes_per_pixel"]
    assert "gbuffer.dir" not in bpp and "gbuffer.t" not in bpp and bpp["gbuffer.tri"] + bpp["gbuffer.bary"] == 12
    assert bpp["prefix_gbuffer.dir"] == 12 and bpp["prefix_gbuffer.t"] == 4
