"""Stage "prefix": prefix generation and temporal reuse, one kernel
(docs/theory/suffix_restir.md#prefix-resampling).

A fresh prefix from each pixel's primary hit (prefix.py): its reservoir (M = 1, W = 1 in primary
sample space, target p_hat = luminance of its throughput) and its end. A pixel with a primary hit
but no prefix end has M = 1 and no prefix. With temporal reuse (and a previous frame), the fresh
prefix is then resampled with the previous frame's resampled prefix of the pixel that saw this
primary hit (reprojection, surface similarity), generalized balance over the two (pairwise with
K = 1), the history's M capped to prefix_cap x the current before any weight. Both prefixes are
shifted (shift_prefix): the history's into this pixel, the fresh one into the previous pixel's
domain (its primary hit under the previous camera). The winner's end becomes this pixel's suffix
domain. The fresh prefix lives in registers only: no buffer holds it between two passes.
Reads: G-buffers (this frame's and the previous), previous camera, previous resampled prefixes
and their G-buffer. Writes: resampled prefixes and their G-buffer (other buffers), events.
"""
import warp as wp

from ...device.camera import Camera
from ...device.color import luminance
from ...device.rng import hash_combine, rng_key, rng_uniform
from ...device.scene_device import SceneDevice
from ...device.streams import SR_PREFIX_TEMPORAL_DIMS_PER_SAMPLE, STAGE_SR_PREFIX, STAGE_SR_PREFIX_TEMPORAL
from ...resampling.mis import talbot_weight2
from ...resampling.ris import cap_history, ris_finalize, ris_init, ris_merge
from ..common.events import EventCounts, packed_events, stage_events
from ..common.gbuffer import GBuffer
from ..common.reuse_domains import NO_PIXEL, temporal_neighbor
from ..common.shading import Shading, load_shading
from .params import KERNEL_MODULE, SRParams
from .prefix import (NO_PREFIX, PrefixReservoir, has_prefix, prefix_end_shading, prefix_flags, shift_prefix,
                     trace_prefix)

CURRENT = wp.constant(0)
HISTORY = wp.constant(1)


@wp.func
def write_end(gb: GBuffer, pixel: int, tri: int, bary: wp.vec2, dist: float, d: wp.vec3):
    gb.tri[pixel] = tri
    gb.bary[pixel] = bary
    gb.t[pixel] = dist
    gb.dir[pixel] = d


@wp.struct
class FreshPrefix:
    """This frame's prefix of a pixel: its reservoir (M = 1, W = 1 in PSS, p_hat = luminance of
    the throughput) and its end (the suffix domain it would give) as traced and as stored."""
    r: PrefixReservoir
    end: Shading
    dist: float
    dir: wp.vec3
    rays: int


@wp.func
def fresh_prefix(scene: SceneDevice, params: SRParams, sh: Shading, pixel: int) -> FreshPrefix:
    f = FreshPrefix()
    f.r.flags = NO_PREFIX
    if sh.valid == 0:
        return f
    key = hash_combine(rng_key(params.pt.seed, params.pt.frame, wp.uint32(STAGE_SR_PREFIX), wp.uint32(pixel)),
                       wp.uint32(params.pt.sample))
    p = trace_prefix(scene, params, sh, key, False)
    f.rays = p.rays
    f.r.M = 1.0
    if p.valid != 0:
        f.r.W = 1.0
        f.r.p_hat = luminance(p.thp)
        f.r.jac = p.jac
        f.r.footprint = p.footprint
        f.r.seed = key
        f.r.flags = prefix_flags(p.length, p.lobe)
        f.end = prefix_end_shading(scene, p)
        f.dist = p.dist
        f.dir = p.dir
    return f


@wp.kernel(module=KERNEL_MODULE)
def prefix_kernel(offset: int, scene: SceneDevice, params: SRParams, temporal: int, camera: Camera,
                  prev_camera: Camera, gb: GBuffer, prev_gb: GBuffer, prev_prefixes: wp.array(dtype=PrefixReservoir),
                  prev_prefix_gb: GBuffer, prefixes: wp.array(dtype=PrefixReservoir), prefix_gb: GBuffer,
                  events: wp.array(dtype=EventCounts)):
    pixel = wp.tid() + offset
    sc = load_shading(scene, gb, pixel)
    fresh = fresh_prefix(scene, params, sc, pixel)
    c = fresh.r
    prefixes[pixel] = c
    write_end(prefix_gb, pixel, wp.where(has_prefix(c), fresh.end.hit.tri, -1), fresh.end.hit.bary, fresh.dist,
              fresh.dir)
    events[pixel] = packed_events(wp.vec4i(0, 0, 0, fresh.rays))
    if temporal == 0 or sc.valid == 0:
        return
    nq = temporal_neighbor(scene, scene, camera, prev_camera, prev_gb, sc, pixel)
    if nq.pixel == NO_PIXEL:
        return
    q = nq.pixel
    r = prev_prefixes[q]
    Mq = cap_history(r.M, params.prefix_cap, c.M)
    q_end = load_shading(scene, prev_prefix_gb, q)
    q_end.valid = wp.where(has_prefix(r), q_end.valid, 0)
    # the history's prefix here, and this prefix at the previous pixel's primary hit
    hist = shift_prefix(scene, params, r, q_end, sc)
    cur = shift_prefix(scene, params, c, fresh.end, nq.sh)
    p_q_at_y = float(0.0)
    d_q_at_y = float(0.0)
    if hist.valid != 0:
        p_q_at_y = luminance(hist.thp)
        d_q_at_y = r.p_hat * Mq
    d_q_at_xc = float(0.0)
    if cur.valid != 0:
        d_q_at_xc = luminance(cur.thp) * cur.J * Mq
    key = rng_key(params.pt.seed, params.pt.frame, wp.uint32(STAGE_SR_PREFIX_TEMPORAL), wp.uint32(pixel))
    base = wp.uint32(params.pt.sample) * wp.uint32(SR_PREFIX_TEMPORAL_DIMS_PER_SAMPLE)
    s = ris_init()
    s = ris_merge(s, talbot_weight2(c.p_hat * c.M, d_q_at_xc, CURRENT), c.p_hat, 1.0, c.W, c.M, CURRENT,
                  rng_uniform(key, base))
    s = ris_merge(s, talbot_weight2(p_q_at_y * c.M * hist.J, d_q_at_y, HISTORY), p_q_at_y, hist.J, r.W, Mq, HISTORY,
                  rng_uniform(key, base + wp.uint32(1)))
    f = ris_finalize(s, 1.0)
    out = c
    if s.selected == HISTORY:
        out = r
        out.p_hat = p_q_at_y
        out.jac = hist.jac
        out.footprint = hist.footprint
        write_end(prefix_gb, pixel, prev_prefix_gb.tri[q], prev_prefix_gb.bary[q], hist.dist, hist.dir)
    elif f.selected == 0:
        out.flags = NO_PREFIX
        write_end(prefix_gb, pixel, -1, wp.vec2(0.0), 0.0, wp.vec3(0.0))
    out.W = f.W
    out.M = f.M
    prefixes[pixel] = out
    failed = wp.where(has_prefix(r) and r.W > 0.0 and hist.valid == 0, 1, 0)
    events[pixel] = packed_events(stage_events(s, failed, fresh.rays + hist.rays + cur.rays))
