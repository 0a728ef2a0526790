"""Stage 3, temporal reuse: the pixel's new reservoir with last frame's final reservoir where
this pixel's primary hit was seen (generalized balance / Talbot MIS over the two;
docs/theory/restir_di.md#temporal-reuse).

The current primary hit is projected into the previous camera; the previous pixel is the
temporal technique if it is on screen, had a primary hit and is geometrically similar (a
decision on G-buffers only). The previous confidence is capped to temporal_cap x the current
one before any weight is computed (cap_history, restir/resampling/ris.py; "no cap" is a cap at
1e6 x, so that spatial reuse, which sums confidences, cannot grow them without bound). Light samples move
as they are: a triangle sample keeps its barycentrics (J: the triangle's area ratio, 1 under rigid
motion), a direction or a delta light itself (J = 1). The previous domain is the previous frame's:
its primary hit, lights and occluders where they were (`prev_scene`; the same scene when nothing
moved), so each target is that of the domain it belongs to
(docs/theory/restir_di.md#temporal-reuse-under-motion). The motion vector is the hit's own.
With visibility-aware targets, each cross-domain target costs one shadow ray (two per pixel).
The shipped kernel, `initial_temporal_kernel`, runs stages 1 and 2 (initial RIS, visibility) and
this one for a pixel in one launch: the new reservoir stays in registers, so no buffer holds it
between the stages, and the spatial rounds write into the history's buffer, which nothing reads
once this kernel has run (24 B per pixel fewer). `stages.split` launches the three stages as
kernels of their own, each timed, with a third reservoir buffer; the same functions in the same
order, so the same images bit for bit.
Reads: scene, previous scene, G-buffer, previous G-buffer and camera, previous final reservoirs (split: and the
reservoirs so far). Writes: reservoirs (split: reservoirs_out), events.
"""
import warp as wp

from ...device.camera import Camera
from ...device.rng import rng_key, rng_uniform
from ...device.scene_device import SceneDevice
from ...device.streams import DI_TEMPORAL_DIMS_PER_SAMPLE, STAGE_DI_TEMPORAL
from ...resampling.mis import talbot_weight2
from ...resampling.ris import cap_history, ris_finalize, ris_init, ris_merge
from ..common.events import EventCounts, packed_events, stage_events
from ..common.gbuffer import GBuffer
from ..common.reuse_domains import NO_PIXEL, temporal_neighbor
from ..common.shading import Shading, load_shading, load_shading_outlined
from .kernel_module import SPLIT_MODULE
from .params import DIParams
from .reservoir import DIReservoir, light_jacobian, own_target, store, target
from .s1_initial import initial_reservoir
from .s2_visibility import visible_reservoir

CURRENT = wp.constant(0)
HISTORY = wp.constant(1)


# The fault injections of this stage (docs/validation.md#power-checks-the-mutation-table), each
# compiled into a module of its own: A1; a 1.5x history weight (a feedback loop); and under scene
# motion, the previous domain evaluated in the current scene.
FAULTS = ("skip_zero_canonical", "overweight_history", "current_scene_history")


def _mutant_module(faults: tuple):
    """A fault-injected build's own Warp module (None: the shipped kernels' module)."""
    return "restir_di" + "".join("_" + f for f in faults) if faults else None


_built: dict = {}


def make_temporal_reuse(*faults: str):
    """The stage's work for one pixel as a function: (reservoir, events) from the pixel's reservoir
    c so far and its shading point sc. `faults` (names in FAULTS) build fault-injected variants for
    the mutation tests; the shipped function is built with none."""
    assert set(faults) <= set(FAULTS), faults
    if faults in _built:
        return _built[faults]
    skip_zero_canonical = "skip_zero_canonical" in faults
    overweight_history = "overweight_history" in faults
    current_scene_history = "current_scene_history" in faults

    @wp.func(module=_mutant_module(faults))
    def temporal_reuse(scene: SceneDevice, prev_scene: SceneDevice, params: DIParams, camera: Camera,
                       prev_camera: Camera, prev_gb: GBuffer, prev_reservoirs: wp.array(dtype=DIReservoir),
                       c: DIReservoir, sc: Shading, pixel: int):
        none = wp.vec4i(0)
        if sc.valid == 0:
            return c, none
        # ---- the temporal technique: where this hit was seen last frame (geometry only)
        nq = temporal_neighbor(prev_scene, prev_scene, camera, prev_camera, prev_gb, sc, pixel)
        if nq.pixel == NO_PIXEL:
            return c, none
        q = nq.pixel
        sq = nq.sh
        vis = params.visibility
        p_c = own_target(scene, sc, c, vis)
        if wp.static(skip_zero_canonical):
            if p_c * c.W == 0.0:
                return c, none
        r = prev_reservoirs[q]
        Mq = cap_history(r.M, params.temporal_cap, c.M)
        key = rng_key(params.seed, params.frame, wp.uint32(STAGE_DI_TEMPORAL), wp.uint32(pixel))
        base = wp.uint32(params.sample) * wp.uint32(DI_TEMPORAL_DIMS_PER_SAMPLE)
        s = ris_init()
        # the previous domain's scene (the mutant: the current one, as if nothing had moved)
        q_scene = prev_scene
        if wp.static(current_scene_history):
            q_scene = scene
        # ---- the current sample, against the history's density for it (its target in the
        # previous domain, over the Jacobian of the move there)
        t_q = target(q_scene, sq, c, vis)
        J_c = light_jacobian(scene, q_scene, c)
        m_c = talbot_weight2(p_c * c.M, wp.where(J_c > 0.0, t_q[0] / J_c, 0.0) * Mq, CURRENT)
        s = ris_merge(s, m_c, p_c, 1.0, c.W, c.M, CURRENT, rng_uniform(key, base))
        # ---- the history's sample, moved to this pixel
        t_c = target(scene, sc, r, vis)
        p_c_at_q = t_c[0]
        J = light_jacobian(scene, q_scene, r)
        m_q = talbot_weight2(p_c_at_q * J * c.M, own_target(q_scene, sq, r, vis) * Mq, HISTORY)
        if wp.static(overweight_history):
            m_q = m_q * 1.5
        s = ris_merge(s, m_q, p_c_at_q, J, r.W, Mq, HISTORY, rng_uniform(key, base + wp.uint32(1)))
        chosen = c
        if s.selected == HISTORY:
            chosen = r
        failed = wp.where(r.W > 0.0 and p_c_at_q <= 0.0, 1, 0)
        return store(chosen, ris_finalize(s, 1.0)), stage_events(s, failed, int(t_q[1] + t_c[1]))

    _built[faults] = temporal_reuse
    return temporal_reuse


temporal_reuse = make_temporal_reuse()


@wp.kernel(module=SPLIT_MODULE)
def temporal_kernel(offset: int, scene: SceneDevice, prev_scene: SceneDevice, params: DIParams, camera: Camera,
                    prev_camera: Camera, gb: GBuffer, prev_gb: GBuffer, prev_reservoirs: wp.array(dtype=DIReservoir),
                    reservoirs: wp.array(dtype=DIReservoir), reservoirs_out: wp.array(dtype=DIReservoir),
                    events: wp.array(dtype=EventCounts)):
    pixel = wp.tid() + offset
    r, ev = temporal_reuse(scene, prev_scene, params, camera, prev_camera, prev_gb, prev_reservoirs,
                           reservoirs[pixel], load_shading(scene, gb, pixel), pixel)
    reservoirs_out[pixel] = r
    events[pixel] = packed_events(ev)


def make_initial_temporal_kernel(*faults: str):
    """The shipped kernel: initial RIS, visibility (params.visibility) and temporal reuse
    (`temporal` != 0) of one pixel in one launch, the mutations as in make_temporal_reuse."""
    reuse = make_temporal_reuse(*faults)

    @wp.kernel(module=_mutant_module(faults))
    def initial_temporal_kernel(offset: int, scene: SceneDevice, prev_scene: SceneDevice, params: DIParams,
                                temporal: int,
                                camera: Camera, prev_camera: Camera, gb: GBuffer, prev_gb: GBuffer,
                                prev_reservoirs: wp.array(dtype=DIReservoir),
                                reservoirs: wp.array(dtype=DIReservoir), events: wp.array(dtype=EventCounts)):
        pixel = wp.tid() + offset
        sc = load_shading_outlined(scene, gb, pixel)
        c, ev = initial_reservoir(scene, params, sc, pixel)
        if params.visibility != 0:
            c, ev_v = visible_reservoir(scene, sc, c)
            ev = ev + ev_v
        if temporal != 0:
            c, ev_t = reuse(scene, prev_scene, params, camera, prev_camera, prev_gb, prev_reservoirs, c, sc, pixel)
            ev = ev + ev_t
        reservoirs[pixel] = c
        events[pixel] = packed_events(ev)

    return initial_temporal_kernel


initial_temporal_kernel = make_initial_temporal_kernel()
