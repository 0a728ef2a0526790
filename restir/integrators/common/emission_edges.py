"""Where the extra camera rays of `emission.rays` are traced: `emission.adaptive`.

The extra rays only lower variance where the emission seen directly varies over a pixel: at the
edge of an emitter (or over a textured one, or the environment). Inside an emitter of constant
radiance, or where no emitter is in view, every ray returns the same value and the n - 1 extra
rays are wasted; on the shared Cornell box at 512 lines they were about a quarter of a
path-tracer frame (BENCHMARKS.md, "The emission seen directly from more camera rays").

So with `emission.adaptive` on, a pixel traces the n rays only where the previous launch of its
stage saw the emission vary in the pixel's 3x3 neighbourhood, and one ray elsewhere. The previous
launch drew its camera positions from other random numbers (another frame or sample in the key),
independent of this launch's, so given the number of rays the pixel's estimate is the mean of
unbiased estimates, as before: the choice can cost variance (an edge that moved out of the
neighbourhood, under camera motion) but never adds bias. Deciding from the sample's own rays
would (the mutation `emission_rays_by_own_ray` of ReSTIR PT, which tests/unit/test_camera.py
catches).

Each launch writes what its rays saw per pixel for the next launch to read (ping-pong: the next
launch reads the buffer this one wrote, and writes the other): the sum of the channels of the
emission its rays saw (one value when they all agreed), or VARIED when they did not. Before the
first launch every pixel reads VARIED: n rays everywhere.
"""
import warp as wp

from ...device.camera import Camera

VARIED = -1.0  # a pixel whose rays saw different emission (emission sums are >= 0)


@wp.func
def emission_sum(Le: wp.vec3) -> float:
    """What neighbouring pixels compare: the emission's channels summed (a change of colour counts)."""
    return Le[0] + Le[1] + Le[2]


@wp.func
def seen(first: float, Le: wp.vec3) -> float:
    """A pixel's record after one more ray saw Le: `first` while the rays agree, else VARIED."""
    return wp.where(first == emission_sum(Le), first, VARIED)


@wp.func
def rays_at(previous: wp.array(dtype=float), camera: Camera, pixel: int, n: int, adaptive: int) -> int:
    """The camera rays the pixel traces for its emission seen directly: n, or with `adaptive` on,
    n only where the previous launch saw the emission vary in its 3x3 neighbourhood, else 1."""
    if n == 1 or adaptive == 0:
        return n
    x = pixel % camera.width
    y = pixel // camera.width
    lo = float(1.0e30)
    hi = float(-1.0e30)
    for dy in range(-1, 2):
        for dx in range(-1, 2):
            xx = x + dx
            yy = y + dy
            if xx >= 0 and xx < camera.width and yy >= 0 and yy < camera.height:
                v = previous[yy * camera.width + xx]
                if v == VARIED:
                    return n
                lo = wp.min(lo, v)
                hi = wp.max(hi, v)
    if hi > lo:
        return n
    return 1


class EmissionEdges:
    """The two per-pixel records (4 B each), made on the first launch that needs them: `previous`
    (read) and `current` (written), swapped after each launch."""

    def __init__(self, integrator):
        self.previous = integrator.buffer("emission_edges", float)
        self.previous.fill_(VARIED)
        self.current = integrator.buffer("emission_edges_next", float)

    def swap(self) -> None:
        self.previous, self.current = self.current, self.previous


def emission_rays(integrator) -> int:
    """The camera rays a sample traces for the emission seen directly: the `emission.rays`
    setting, or 1 with pixel-centre rays (RenderConfig.jitter off), where every ray would be the
    sample's own."""
    return int(integrator.settings.emission_rays) if integrator.dscene.jitter else 1


def emission_edges(integrator) -> EmissionEdges | None:
    """The integrator's records, or None where no launch reads them (one ray, or adaptive off)."""
    if emission_rays(integrator) == 1 or not integrator.settings.emission_adaptive:
        return None
    edges = getattr(integrator, "_emission_edges", None)
    if edges is None:
        edges = integrator._emission_edges = EmissionEdges(integrator)
    return edges


_NONE = {}


def edge_arrays(integrator, edges: EmissionEdges | None) -> tuple:
    """(previous, current) for the kernels: the records, or two empty arrays the kernel never
    touches (it reads them only when n > 1 and adaptive)."""
    if edges is not None:
        return edges.previous, edges.current
    device = str(integrator.device)
    if device not in _NONE:
        _NONE[device] = wp.empty(0, dtype=float, device=integrator.device)
    return _NONE[device], _NONE[device]
