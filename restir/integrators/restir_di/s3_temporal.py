"""Stage 3, temporal reuse: the pixel's new reservoir with last frame's final reservoir where
this pixel's primary hit was seen (generalized balance / Talbot MIS over the two;
docs/theory/restir_di.md#temporal-reuse).

The current primary hit is projected into the previous camera; the previous pixel is the
temporal technique if it is on screen, had a primary hit and is geometrically similar (a
decision on G-buffers only). The previous confidence is capped to temporal_cap x the current
one before any weight is computed (cap_history, restir/resampling/ris.py; "no cap" is a cap at
1e6 x, so that spatial reuse, which sums confidences, cannot grow them without bound). Light samples move
unchanged (J = 1). Static scenes: the previous domain is evaluated with the current geometry.
With visibility-aware targets, each cross-domain target costs one shadow ray (two per pixel).
The shipped kernel, `initial_temporal_kernel`, runs stages 1 and 2 (initial RIS, visibility) and
this one for a pixel in one launch: the new reservoir stays in registers, so no buffer holds it
between the stages, and the spatial rounds write into the history's buffer, which nothing reads
once this kernel has run (24 B per pixel fewer). `stages.split` launches the three stages as
kernels of their own, each timed, with a third reservoir buffer; the same functions in the same
order, so the same images bit for bit.
Reads: scene, G-buffer, previous G-buffer and camera, previous final reservoirs (split: and the
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
from .reservoir import DIReservoir, own_target, store, target
from .s1_initial import initial_reservoir
from .s2_visibility import visible_reservoir

CURRENT = wp.constant(0)
HISTORY = wp.constant(1)


def _mutant_module(skip_zero_canonical: bool, overweight_history: bool):
    """A fault-injected build's own Warp module (None: the shipped kernels' module)."""
    if not (skip_zero_canonical or overweight_history):
        return None
    return "restir_di" + "_skip_zero_canonical" * skip_zero_canonical + "_overweight_history" * overweight_history


_built: dict = {}


def make_temporal_reuse(skip_zero_canonical: bool = False, overweight_history: bool = False):
    """The stage's work for one pixel as a function: (reservoir, events) from the pixel's reservoir
    c so far and its shading point sc. The arguments build fault-injected variants for the
    mutation tests (docs/validation.md#power-checks-the-mutation-table: A1, and a 1.5x history
    weight, a feedback loop), compiled
    into modules of their own; the shipped function is built with neither."""
    if (skip_zero_canonical, overweight_history) in _built:
        return _built[skip_zero_canonical, overweight_history]

    @wp.func(module=_mutant_module(skip_zero_canonical, overweight_history))
    def temporal_reuse(scene: SceneDevice, params: DIParams, camera: Camera, prev_camera: Camera, prev_gb: GBuffer,
                       prev_reservoirs: wp.array(dtype=DIReservoir), c: DIReservoir, sc: Shading, pixel: int):
        none = wp.vec4i(0)
        if sc.valid == 0:
            return c, none
        # ---- the temporal technique: where this hit was seen last frame (geometry only)
        nq = temporal_neighbor(scene, camera, prev_camera, prev_gb, sc, pixel)
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
        # ---- the current sample, against the history's density for it
        t_q = target(scene, sq, c, vis)
        m_c = talbot_weight2(p_c * c.M, t_q[0] * Mq, CURRENT)
        s = ris_merge(s, m_c, p_c, 1.0, c.W, c.M, CURRENT, rng_uniform(key, base))
        # ---- the history's sample, moved to this pixel (J = 1)
        t_c = target(scene, sc, r, vis)
        p_c_at_q = t_c[0]
        m_q = talbot_weight2(p_c_at_q * c.M, own_target(scene, sq, r, vis) * Mq, HISTORY)
        if wp.static(overweight_history):
            m_q = m_q * 1.5
        s = ris_merge(s, m_q, p_c_at_q, 1.0, r.W, Mq, HISTORY, rng_uniform(key, base + wp.uint32(1)))
        chosen = c
        if s.selected == HISTORY:
            chosen = r
        failed = wp.where(r.W > 0.0 and p_c_at_q <= 0.0, 1, 0)
        return store(chosen, ris_finalize(s, 1.0)), stage_events(s, failed, int(t_q[1] + t_c[1]))

    _built[skip_zero_canonical, overweight_history] = temporal_reuse
    return temporal_reuse


temporal_reuse = make_temporal_reuse()


@wp.kernel(module=SPLIT_MODULE)
def temporal_kernel(offset: int, scene: SceneDevice, params: DIParams, camera: Camera, prev_camera: Camera,
                    gb: GBuffer, prev_gb: GBuffer, prev_reservoirs: wp.array(dtype=DIReservoir),
                    reservoirs: wp.array(dtype=DIReservoir), reservoirs_out: wp.array(dtype=DIReservoir),
                    events: wp.array(dtype=EventCounts)):
    pixel = wp.tid() + offset
    r, ev = temporal_reuse(scene, params, camera, prev_camera, prev_gb, prev_reservoirs, reservoirs[pixel],
                           load_shading(scene, gb, pixel), pixel)
    reservoirs_out[pixel] = r
    events[pixel] = packed_events(ev)


def make_initial_temporal_kernel(skip_zero_canonical: bool = False, overweight_history: bool = False):
    """The shipped kernel: initial RIS, visibility (params.visibility) and temporal reuse
    (`temporal` != 0) of one pixel in one launch, the mutations as in make_temporal_reuse."""
    reuse = make_temporal_reuse(skip_zero_canonical, overweight_history)

    @wp.kernel(module=_mutant_module(skip_zero_canonical, overweight_history))
    def initial_temporal_kernel(offset: int, scene: SceneDevice, params: DIParams, temporal: int,
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
            c, ev_t = reuse(scene, params, camera, prev_camera, prev_gb, prev_reservoirs, c, sc, pixel)
            ev = ev + ev_t
        reservoirs[pixel] = c
        events[pixel] = packed_events(ev)

    return initial_temporal_kernel


initial_temporal_kernel = make_initial_temporal_kernel()
