"""Stage 3, MCMC suffix mutations (`mcmc.steps` > 0): each pixel's sample after temporal reuse
gets a fixed number of Metropolis steps on its path after the rc vertex z, or after rcPrev
(`mcmc.start`; path_reuse/suffix_mutation.py; docs/guide/decorrelation.md 2). A step proposes a fresh suffix,
evaluates it in this pixel's domain with the shift (the sample's own domain: J = 1), and accepts
with min(1, p_hat(Y) / p_hat(X)); on acceptance W becomes W p_hat(X) / p_hat(Y). M does not
change (confidence is never a sample value), and neither does the number of steps: it is a
setting, the same for every sample. The pixel's own estimate keeps its luminance (p_hat(Y) W_Y
= p_hat(X) W_X); what changes is what spatial reuse and the next frame copy: a sample many
pixels share gets a different suffix in each. Measured, that changes the error's correlation
by no more than the run's noise
(docs/guide/decorrelation.md#3-mcmc-mutations-built-and-measured-they-do-not-decorrelate), so it is off by default.

Runs between temporal and spatial reuse, reading only the pixel's own reservoir.
Reads: scene, G-buffer, reservoirs. Writes: reservoirs_out (ping-pong), counts (samples that have
a suffix, valid proposals, accepted), events (rays).
"""
import warp as wp

from ...device.color import luminance
from ...device.rng import hash_combine, rng_key, rng_uniform
from ...device.scene_device import SceneDevice
from ...device.streams import PT_MAX_MCMC_STEPS, PT_MCMC_DIM_ACCEPT, STAGE_PT_MCMC
from ..common.events import EventCounts, PassCounts, packed_counts, packed_events, ray_events
from ..common.gbuffer import GBuffer
from ..common.shading import load_shading
from ..path_reuse.domain import domain_at
from ..path_reuse.params import PathReuseParams
from ..path_reuse.path_sample import PathReservoir, rc_length
from ..path_reuse.shift import replay_prefix, shift_path
from ..path_reuse.suffix_mutation import mutable, propose_suffix
from .kernel_module import KERNEL_MODULE

MUTATIONS = ("keep_w",)


def make_mcmc_kernel(mutation: str = "none", module=None):
    """The mutation kernel; `mutation` builds a fault-injected variant: keep_w (W not updated on
    acceptance)."""
    assert mutation == "none" or mutation in MUTATIONS, mutation
    keep_w = mutation == "keep_w"

    @wp.kernel(module=module or KERNEL_MODULE)
    def mcmc_kernel(offset: int, scene: SceneDevice, params: PathReuseParams, steps: int, from_rc_prev: int, gb: GBuffer,
                    reservoirs: wp.array(dtype=PathReservoir), reservoirs_out: wp.array(dtype=PathReservoir),
                    counts: wp.array(dtype=PassCounts), events: wp.array(dtype=EventCounts)):
        pixel = wp.tid() + offset
        r = reservoirs[pixel]
        reservoirs_out[pixel] = r
        counts[pixel] = packed_counts(wp.vec4i(0))
        events[pixel] = packed_events(wp.vec4i(0))
        if not mutable(r):
            return
        sh = load_shading(scene, gb, pixel)
        if sh.valid == 0:
            return
        dc = domain_at(sh, params)
        # the pixel's prefix to rcPrev, fixed for every step (the sample's seed and this domain)
        y = replay_prefix(scene, params, sh, r.seed, rc_length(r.flags) - 1)
        rays = y.rays
        n = wp.vec4i(1, 0, 0, 0)
        if y.valid != 0:
            key0 = rng_key(params.seed, params.frame, wp.uint32(STAGE_PT_MCMC), wp.uint32(pixel))
            for step in range(steps):
                key = hash_combine(key0, wp.uint32(params.sample * PT_MAX_MCMC_STEPS + step))
                p = propose_suffix(scene, params, r, y, key, from_rc_prev)
                rays += p.rays
                if p.valid == 0:
                    continue
                t = shift_path(scene, p.r, dc)  # the proposal's F here (its own domain)
                rays += t.rays
                if t.valid == 0:
                    continue
                n[1] += 1
                p_x = luminance(r.F)
                p_y = luminance(t.r.F)
                if rng_uniform(key, wp.uint32(PT_MCMC_DIM_ACCEPT)) * p_x < p_y:
                    W = r.W * p_x / p_y
                    if wp.static(keep_w):
                        W = r.W
                    r = t.r
                    r.W = W
                    n[2] += 1
        reservoirs_out[pixel] = r
        counts[pixel] = packed_counts(n)
        events[pixel] = packed_events(ray_events(rays))

    return mcmc_kernel


mcmc_kernel = make_mcmc_kernel()
