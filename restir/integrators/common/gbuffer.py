"""The G-buffer: each pixel's primary hit, stored compactly and rebuilt on demand (shading.py).

One `GBuffer` struct of arrays travels to every stage as one argument. Methods with temporal
reuse keep two, the current and the previous frame's, as a `PingPong` pair whose `swap()` is the
one visible place where this frame's data becomes history.
"""
import warp as wp


@wp.struct
class GBuffer:
    tri: wp.array(dtype=wp.int32)   # primary-hit triangle; -1: the camera ray escaped
    bary: wp.array(dtype=wp.vec2)   # barycentrics of the hit in that triangle
    t: wp.array(dtype=float)        # ray distance camera -> hit
    dir: wp.array(dtype=wp.vec3)    # primary ray direction (world, unit)


def allocate_gbuffer(integrator, name: str) -> GBuffer:
    """A G-buffer whose arrays are registered with the integrator's memory stats as name.*"""
    gb = GBuffer()
    gb.tri = integrator.buffer(f"{name}.tri", wp.int32)
    gb.bary = integrator.buffer(f"{name}.bary", wp.vec2)
    gb.t = integrator.buffer(f"{name}.t", float)
    gb.dir = integrator.buffer(f"{name}.dir", wp.vec3)
    return gb


class PingPong:
    """Two buffers (arrays or structs of arrays): `current` is written this frame, `previous`
    holds the last frame's and is only read. `swap()` exchanges them, once per frame/sample."""

    def __init__(self, current, previous):
        self.current = current
        self.previous = previous

    def swap(self) -> None:
        self.current, self.previous = self.previous, self.current
