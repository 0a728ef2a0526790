"""Where the extra camera rays of `emission.rays` are traced: `emission.adaptive`.

The extra rays only lower variance where the emission seen directly varies over a pixel: at the
edge of an emitter (or over a textured one, or the environment). Inside an emitter of constant
radiance, or where no emitter is in view, every ray returns the same value and the n - 1 extra
rays are wasted; on the shared Cornell box at 512 lines they were about a quarter of a
path-tracer frame (docs/guide/when_restir_pays.md#only-near-the-emitters-edges).

So with `emission.adaptive` on, a pixel traces the n rays only where earlier launches of its stage
saw the emission vary nearby, and one ray elsewhere: where the previous launch saw it vary in the
pixel's 3x3 neighbourhood, or any of the MEMORY launches before did. The memory keeps the rays on
an emitter smaller than a pixel, which one ray a launch sees only now and then. Earlier launches
drew their camera positions from other random numbers (another frame or sample in the key),
independent of this launch's, so given the number of rays the pixel's estimate is the mean of
unbiased estimates, as before: the choice can cost variance (an edge that moved out of the
neighbourhood, under camera motion) but never adds bias. Deciding from the sample's own rays
would (the mutation `emission_rays_by_own_ray` of ReSTIR PT, which tests/unit/test_camera.py
catches).

Each launch writes a record per pixel for the next launch to read (ping-pong: the next launch
reads the buffer this one wrote, and writes the other): what its rays saw (the sum of the
channels of their emission when they all agreed, else VARIED) and the launches since variation
was last seen around the pixel (0: in this launch's rays or the previous launch's
neighbourhood). The first launch reads UNKNOWN everywhere and traces the n rays at every pixel.

Rays see an emitter smaller than a pixel too rarely for that: one covering 2% of a pixel is seen
by one ray a launch about once in 50 launches (veach-mis's smallest light at 32x32 was found in
none of 32 frames, and its pixels kept one ray). So every launch also marks, from the geometry
alone, the pixels near any emissive triangle whose projection spans at most SMALL_EMITTER_PX
pixels (`small_emitters_kernel`): they take the n rays whatever earlier launches saw. The marks
depend on the scene and the camera only, so they are as unbiased a choice as the records.
"""
import contextlib
from typing import NamedTuple

import warp as wp

from ...device.camera import Camera, project_to_pixel
from ...device.scene_device import SceneDevice

VARIED = -1.0  # a pixel whose rays saw different emission (emission sums are >= 0)
UNKNOWN = -2.0  # before the first launch
MEMORY = 16    # launches a pixel keeps the n rays after it last saw the emission vary around it
SMALL_EMITTER_PX = 2.0  # emissive triangles whose screen bounds are at most this wide get marked pixels


@wp.func
def emission_sum(Le: wp.vec3) -> float:
    """What neighbouring pixels compare: the emission's channels summed (a change of colour counts)."""
    return Le[0] + Le[1] + Le[2]


@wp.func
def seen(first: float, Le: wp.vec3) -> float:
    """A pixel's record after one more ray saw Le: `first` while the rays agree, else VARIED."""
    return wp.where(first == emission_sum(Le), first, VARIED)


@wp.struct
class EdgeChoice:
    rays: int    # the camera rays the pixel traces for its emission seen directly
    age: float   # launches since variation was last seen around the pixel, the previous one's included


NOT_SEEN, VARIED_NEARBY, FIRST_LAUNCH = 0, 1, 2


@wp.func
def varied_nearby(previous: wp.array(dtype=wp.vec2), camera: Camera, pixel: int) -> int:
    """Whether the previous launch saw the emission vary in the pixel's 3x3 neighbourhood (a pixel
    whose rays disagreed, or two pixels that saw different emission): VARIED_NEARBY or NOT_SEEN;
    FIRST_LAUNCH before any launch."""
    x = pixel % camera.width
    y = pixel // camera.width
    lo = float(1.0e30)
    hi = float(-1.0e30)
    for dy in range(-1, 2):
        for dx in range(-1, 2):
            xx = x + dx
            yy = y + dy
            if xx >= 0 and xx < camera.width and yy >= 0 and yy < camera.height:
                v = previous[yy * camera.width + xx][0]
                if v == UNKNOWN:
                    return FIRST_LAUNCH
                if v == VARIED:
                    return VARIED_NEARBY
                lo = wp.min(lo, v)
                hi = wp.max(hi, v)
    return wp.where(hi > lo, VARIED_NEARBY, NOT_SEEN)


@wp.func
def edge_choice(previous: wp.array(dtype=wp.vec2), marks: wp.array(dtype=wp.uint8), camera: Camera, pixel: int,
                n: int, adaptive: int) -> EdgeChoice:
    """n rays, or with `adaptive` on, n only where variation was seen around the pixel in the last
    MEMORY launches (emission_edges.py), in the first launch and where a small emitter is near
    (`marks`), else 1: from earlier launches' records and the geometry alone."""
    c = EdgeChoice()
    c.rays = n
    if n == 1 or adaptive == 0:
        return c
    seen_nearby = varied_nearby(previous, camera, pixel)
    age = previous[pixel][1]  # the first launch's: MEMORY + 1, never seen
    if seen_nearby == VARIED_NEARBY:
        age = 0.0
    elif seen_nearby == NOT_SEEN:
        age += 1.0
    c.age = age
    if age > float(MEMORY) and seen_nearby != FIRST_LAUNCH and marks[pixel] == wp.uint8(0):
        c.rays = 1
    return c


@wp.kernel
def small_emitters_kernel(scene: SceneDevice, camera: Camera, marks: wp.array(dtype=wp.uint8)):
    """Light triangle i: if its projection's bounds span at most SMALL_EMITTER_PX pixels, mark the
    pixels whose filter can reach it (the bounds grown by the filter's radius and a pixel).
    Every writer writes the same 1, so the order of the threads cannot matter."""
    tri = scene.light_tri[wp.tid()]
    lo = wp.vec2(1.0e30)
    hi = wp.vec2(-1.0e30)
    for k in range(3):
        q = project_to_pixel(camera, scene.positions[3 * tri + k])
        if q[0] == -1.0 and q[1] == -1.0:
            return  # partly behind the camera: not small on screen
        lo = wp.min(lo, q)
        hi = wp.max(hi, q)
    if hi[0] - lo[0] > SMALL_EMITTER_PX or hi[1] - lo[1] > SMALL_EMITTER_PX:
        return
    pad = wp.ceil(camera.filter_radius) + 1.0
    x0 = wp.max(int(wp.floor(lo[0] - pad)), 0)
    x1 = wp.min(int(wp.floor(hi[0] + pad)), camera.width - 1)
    y0 = wp.max(int(wp.floor(lo[1] - pad)), 0)
    y1 = wp.min(int(wp.floor(hi[1] + pad)), camera.height - 1)
    for y in range(y0, y1 + 1):
        for x in range(x0, x1 + 1):
            marks[y * camera.width + x] = wp.uint8(1)


@wp.func
def edge_record(c: EdgeChoice, record: float) -> wp.vec2:
    """What this launch leaves the next about the pixel: what its rays saw (`record`), and the
    age of the variation seen around it (0 when its own rays disagreed)."""
    return wp.vec2(record, wp.where(record == VARIED, 0.0, wp.min(c.age, float(MEMORY + 1))))


class EmissionEdges:
    """The two per-pixel records (8 B each), made on the first launch that needs them: `previous`
    (read) and `current` (written), swapped after each launch; and the small emitters' marks (1 B),
    made again before each launch (`mark`) from its camera."""

    def __init__(self, integrator):
        self.previous = integrator.buffer("emission_edges", wp.vec2)
        self.previous.fill_(wp.vec2(UNKNOWN, float(MEMORY + 1)))
        self.current = integrator.buffer("emission_edges_next", wp.vec2)
        self.marks = integrator.buffer("emission_edges_marks", wp.uint8)

    def mark(self, integrator, camera) -> None:
        """The launch's marks: pixels near an emitter too small for the records to find."""
        self.marks.zero_()
        scene = integrator.dscene
        if scene.scene.num_tri_lights > 0:
            wp.launch(small_emitters_kernel, dim=scene.scene.num_tri_lights, inputs=[scene.scene, camera],
                      outputs=[self.marks], device=integrator.device)

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


class EdgeLaunch(NamedTuple):
    """What one launch of a stage passes its kernel: adaptive (0 or 1), the records it reads and
    writes, the marks, and new_call for the stage's timer (False once the marks were timed)."""
    adaptive: int
    previous: wp.array
    marks: wp.array
    current: wp.array
    new_call: bool


_EMPTY = {}


@contextlib.contextmanager
def edge_launch(integrator, stage: str, camera, new_call: bool = True):
    """One launch of `stage` with `camera`: with emission.adaptive on, its marks made (timed as part
    of the stage) before, the records swapped after; otherwise empty arrays the kernels never touch
    (they read them only when n > 1 and adaptive) and nothing else done."""
    edges = emission_edges(integrator)
    if edges is None:
        device = str(integrator.device)
        if device not in _EMPTY:
            _EMPTY[device] = (wp.empty(0, dtype=wp.vec2, device=integrator.device),
                              wp.empty(0, dtype=wp.uint8, device=integrator.device))
        records, marks = _EMPTY[device]
        yield EdgeLaunch(0, records, marks, records, new_call)
        return
    with integrator.timer.stage(integrator.stage_prefix + stage, new_call):
        edges.mark(integrator, camera)
    yield EdgeLaunch(1, edges.previous, edges.marks, edges.current, False)
    edges.swap()
