"""The G-buffer: each pixel's primary hit, stored compactly and rebuilt on demand (shading.py).

One `GBuffer` struct of arrays travels to every stage as one argument. Methods with temporal
reuse keep two, the current and the previous frame's, as a `PingPong` pair whose `swap()` is the
one visible place where this frame's data becomes history.

A hit is its triangle and barycentrics (12 B). The ray that found it (its distance and direction,
16 B more) is stored only where its origin is a vertex of the path (Suffix ReSTIR's prefix ends)
or a point on a thin lens; every primary ray of a pinhole camera starts at its position, so a
primary-hit G-buffer keeps that position once and rebuilds the ray from it and the hit: the same
numbers to float rounding, 32 B a pixel less for a method with two G-buffers.
"""
import numpy as np
import warp as wp


@wp.struct
class GBuffer:
    tri: wp.array(dtype=wp.int32)   # the hit's triangle; -1: the ray escaped
    bary: wp.array(dtype=wp.vec2)   # barycentrics of the hit in that triangle
    t: wp.array(dtype=float)        # ray distance origin -> hit (stored rays only)
    dir: wp.array(dtype=wp.vec3)    # ray direction (world, unit; stored rays only)
    origin: wp.vec3                 # every ray's origin, the camera position (from_camera = 1)
    from_camera: int                # 1: t and dir rebuilt from origin and the hit; 0: stored


def allocate_gbuffer(integrator, name: str, store_rays: bool = False) -> GBuffer:
    """A G-buffer whose arrays are registered with the integrator's memory stats as name.*.
    store_rays: keep each hit's ray (for hits whose rays do not all start at the camera)."""
    gb = GBuffer()
    gb.tri = integrator.buffer(f"{name}.tri", wp.int32)
    gb.bary = integrator.buffer(f"{name}.bary", wp.vec2)
    gb.from_camera = 0 if store_rays else 1
    if store_rays:
        gb.t = integrator.buffer(f"{name}.t", float)
        gb.dir = integrator.buffer(f"{name}.dir", wp.vec3)
    return gb


LENS_MUTATION = "lens_rays_from_centre"  # a fault injection of the pipelines (common/mutations.py)


def allocate_primary_gbuffer(integrator, name: str) -> GBuffer:
    """A G-buffer of primary hits: the rays are rebuilt from the camera's position, or stored
    where a thin lens starts each at a point of its own. (The mutation LENS_MUTATION rebuilds a
    thin lens's rays from the lens's centre: every primary hit then sees a direction toward the
    camera that is not its ray's.)"""
    thin_lens = integrator.dscene.camera.aperture_radius > 0.0
    if getattr(integrator.settings, "debug_mutation", "none") == LENS_MUTATION:
        thin_lens = False
    return allocate_gbuffer(integrator, name, store_rays=thin_lens)


def set_camera_origin(gb: GBuffer, camera) -> None:
    """Before a frame's primary hits are written into gb: the position its rays start from
    (the camera's, as generate_ray computes it: to_world applied to the local origin)."""
    m = np.array(camera.to_world, dtype=np.float32).reshape(4, 4)
    gb.origin = wp.vec3(*(float(x) for x in m[:3, 3]))


class PingPong:
    """Two buffers (arrays or structs of arrays): `current` is written this frame, `previous`
    holds the last frame's and is only read. `swap()` exchanges them, once per frame/sample."""

    def __init__(self, current, previous):
        self.current = current
        self.previous = previous

    def swap(self) -> None:
        self.current, self.previous = self.previous, self.current
