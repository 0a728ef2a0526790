"""Stage 1, trace and initial RIS: `candidates` base paths per pixel from its primary hit, every
event of every path streamed into one reservoir (base_path.py;
docs/theory/restir_pt.md#initial-resampling-over-path-lengths):
w = p_hat(F) / C per event, W = w_sum / p_hat(selected), M = C (one per traced path, never one
per event). Pixels without a primary hit keep an empty reservoir of M = 0.

By default this stage runs fused with temporal reuse (s2_temporal.py: one kernel, the new
reservoir never stored); `stages.split` launches it as a kernel of its own, timed apart.
With direct=nee the stage also writes the pixel's direct light: the emission seen directly plus
its base paths' summed events at x_0, times the filter weight (the shade stage adds it).
Reads: scene, G-buffer, emission, filter weights. Writes: reservoirs, direct light (direct=nee),
events (non-finite and zero weights, rays).
"""
import warp as wp

from ...device.rng import hash_combine, rng_key
from ...device.scene_device import SceneDevice
from ...device.streams import STAGE_PT_PATHS, STAGE_PT_RIS
from ...resampling.ris import ris_finalize, ris_init
from ..common.events import EventCounts, packed_events, stage_events
from ..common.gbuffer import GBuffer
from ..common.shading import Shading, load_shading
from ..path_reuse.base_path import EVENTS_PER_PATH, BasePath, trace_base_path
from ..path_reuse.params import PathReuseParams
from ..path_reuse.path_sample import empty_path, store
from ..path_reuse.path_sample import PathReservoir
from .kernel_module import KERNEL_MODULE, SPLIT_MODULE

_built: dict = {}


def make_initial_reservoir(m_per_event: bool = False):
    """The stage's work for one pixel as a function, (reservoir, events, the summed events at x_0
    of direct=nee) from its shading point:
    what the split kernel stores and the fused kernel keeps in registers. m_per_event builds the
    mutation that counts M per streamed event (and divides W by it), the defect
    docs/validation.md#power-checks-the-mutation-table lists; the shipped function is built without it."""
    if m_per_event in _built:
        return _built[m_per_event]

    @wp.func(module="restir_pt_m_per_event" if m_per_event else KERNEL_MODULE)
    def initial_reservoir(scene: SceneDevice, params: PathReuseParams, sh: Shading, pixel: int):
        acc = BasePath()
        acc.s = ris_init()
        acc.r = empty_path()
        out = empty_path()
        if sh.valid != 0:
            path_key = rng_key(params.seed, params.frame, wp.uint32(STAGE_PT_PATHS), wp.uint32(pixel))
            ris_key = rng_key(params.seed, params.frame, wp.uint32(STAGE_PT_RIS), wp.uint32(pixel))
            for c in range(params.candidates):
                path_id = wp.uint32(params.sample * params.candidates + c)
                acc = trace_base_path(scene, params, sh, hash_combine(path_key, path_id),
                                      hash_combine(ris_key, path_id), c * EVENTS_PER_PATH, acc)
            f = ris_finalize(acc.s, 1.0)
            f.M = float(params.candidates)
            if wp.static(m_per_event):
                n = float(acc.s.count)  # the defect: M = events streamed, and W = w_sum / (p_hat M)
                f = ris_finalize(acc.s, wp.max(1.0, n) / float(params.candidates))
                f.M = wp.max(1.0, n)
            out = store(acc.r, f)
        return out, stage_events(acc.s, 0, acc.rays), acc.direct

    _built[m_per_event] = initial_reservoir
    return initial_reservoir


initial_reservoir = make_initial_reservoir()


@wp.func
def store_direct(params: PathReuseParams, pixel: int, summed: wp.vec3, emission: wp.array(dtype=wp.vec3),
                 primary_weight: wp.array(dtype=float), direct: wp.array(dtype=wp.vec3)):
    """direct=nee: the pixel's direct light for the shade stage, the emission seen directly plus
    the base paths' summed events at x_0 times the filter weight (with another `direct`, nothing)."""
    if params.direct_nee != 0:
        direct[pixel] = emission[pixel] + summed * primary_weight[pixel]


@wp.kernel(module=SPLIT_MODULE)
def initial_kernel(offset: int, scene: SceneDevice, params: PathReuseParams, gb: GBuffer,
                   emission: wp.array(dtype=wp.vec3), primary_weight: wp.array(dtype=float),
                   reservoirs: wp.array(dtype=PathReservoir), direct: wp.array(dtype=wp.vec3),
                   events: wp.array(dtype=EventCounts)):
    """The stage on its own (`stages.split`)."""
    pixel = wp.tid() + offset
    r, ev, d = initial_reservoir(scene, params, load_shading(scene, gb, pixel), pixel)
    reservoirs[pixel] = r
    store_direct(params, pixel, d, emission, primary_weight, direct)
    events[pixel] = packed_events(ev)
