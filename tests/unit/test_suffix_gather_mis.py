"""D1 for the final gather (docs/validation.md#level-0-deterministic-property-tests;
docs/guide/suffix_restir.md, "The final gather"): for a suffix
y of a fresh prefix's domain, the weights the gather gives y from every technique that can
produce it sum to 1, computed by the gather's own functions (s5_gather.make_gather:
neighbor_term, canonical_weight) with real shifts, on real frames of Suffix ReSTIR (its search
structure, prefixes and suffix reservoirs).

Per pixel: a fresh prefix is traced and its slots filled as the gather fills them; y is a suffix
traced at its end (the canonical technique's sample). Each slot technique k can produce y from
x_k = T_c->k(y) when that shift succeeds; its weight at y is what neighbor_term gives x_k as slot
k's sample (with slot k's confidence). m_c(y) + sum_k m_k(x_k) must be 1 within 1e-4 (Talbot and
pairwise), whatever slot k's reservoir holds: an empty reservoir is still a technique. The
mutant that drops slots with empty reservoirs from the technique set must break it.
"""
import numpy as np
import pytest
import warp as wp

import restir
from restir.api import make_integrator
from restir.device.rng import hash_combine, rng_key
from restir.device.scene_device import SceneDevice
from restir.integrators.common.gbuffer import GBuffer
from restir.integrators.common.shading import load_shading
from restir.integrators.path_reuse.path_sample import PathReservoir, holds_path
from restir.integrators.path_reuse.reuse_pair import make_reuse_pair
from restir.integrators.path_reuse.shift import shift_path
from restir.integrators.suffix_restir.domains import Domain, load_domain, suffix_params
from restir.integrators.suffix_restir.params import SRParams
from restir.integrators.suffix_restir.prefix import PrefixReservoir, prefix_end_shading, trace_prefix
from restir.integrators.suffix_restir.s5_gather import canonical_suffix, fill_slots, make_gather
from restir.integrators.suffix_restir.s2_search import NO_PIXEL, SearchStructure, nearest_prefix_ends

TOL = 1e-4
N_OUT = 4  # [tested, sum of weights, techniques that produce y besides the canonical, slots whose reservoir is empty]


@wp.func
def as_sample(r: PathReservoir) -> PathReservoir:
    out = r
    out.W = 1.0
    return out


def make_kernel(gather):
    _, shift_out, _, _ = make_reuse_pair(shift_path)

    @wp.kernel(module="unique")
    def gather_mis_kernel(scene: SceneDevice, params: SRParams, gb: GBuffer, search: SearchStructure,
                          prefixes: wp.array(dtype=PrefixReservoir), prefix_gb: GBuffer,
                          suffixes: wp.array(dtype=PathReservoir), width: int, height: int,
                          out: wp.array2d(dtype=float)):
        pixel = wp.tid()
        for col in range(N_OUT):
            out[pixel, col] = 0.0
        sc = load_shading(scene, gb, pixel)
        if sc.valid == 0:
            return
        key = rng_key(params.pt.seed, wp.uint32(77), wp.uint32(3), wp.uint32(pixel))
        pf = trace_prefix(scene, params, sc, hash_combine(key, wp.uint32(0)), False)
        if pf.valid == 0:
            return
        dst = Domain()
        dst.sh = prefix_end_shading(scene, pf)
        dst.params = suffix_params(params, pf.length)
        slots = nearest_prefix_ends(search, pf.hit.p, params.gather_suffixes)
        slots = fill_slots(slots, params, prefixes, pixel, width, height, key, wp.uint32(100))
        y = canonical_suffix(scene, dst, hash_combine(key, wp.uint32(1)), hash_combine(key, wp.uint32(2))).r
        if not holds_path(y) or y.W <= 0.0:
            return
        total = gather.canonical_weight(scene, params, slots, y, prefixes, prefix_gb, suffixes)
        producing = int(0)
        empty = int(0)
        for k in range(params.gather_suffixes):
            n = slots.pixel[k]
            if n == NO_PIXEL:
                continue
            if not holds_path(suffixes[n]) or suffixes[n].W <= 0.0:
                empty += 1
            dk = load_domain(scene, params, prefixes, prefix_gb, n)
            xk = shift_out(scene, y, 1.0, dk)  # y as technique k would have sampled it
            if xk.t.valid == 0:
                continue
            t = gather.neighbor_term(scene, params, dst, slots, k, as_sample(xk.t.r), prefixes, prefix_gb, suffixes)
            total += t.m
            producing += 1
        out[pixel, 0] = 1.0
        out[pixel, 1] = total
        out[pixel, 2] = float(producing)
        out[pixel, 3] = float(empty)

    return gather_mis_kernel


_kernels = {}


def gather_sums(scene_spec, settings, mutation="none", size=48, device="cpu"):
    if mutation not in _kernels:
        g = make_gather() if mutation == "none" else make_gather(module="unique", mutation=mutation)
        _kernels[mutation] = make_kernel(g)
    scene = restir.load_scene(scene_spec, width=size, height=size)
    cfg = restir.RenderConfig(method="suffix-restir", spp=1, max_depth=5, seed=3, settings=settings, device=device)
    integ = make_integrator(scene, cfg)
    integ.render_frame(0)  # the history: resampled prefixes, boxes, final suffixes (then swapped)
    integ.render_frame(1)
    out = wp.zeros((integ.num_pixels, N_OUT), dtype=float, device=integ.device)
    # the last frame's search structure and buffers (its final suffixes and prefixes are now "previous")
    wp.launch(_kernels[mutation], dim=integ.num_pixels, device=integ.device,
              inputs=[integ.dscene.scene, integ.params(1, 0), integ.gbuffers.previous, integ.search,
                      integ.prefixes.previous, integ.prefix_gbs.previous, integ.reservoirs.previous,
                      integ.width, integ.height, out])
    o = out.numpy()
    return o[o[:, 0] > 0]


@pytest.mark.gpu
@pytest.mark.parametrize("mis", ["talbot", "pairwise"])
@pytest.mark.parametrize("scene", ["builtin:indirect-room", "builtin:cornell-box-glossy"])
def test_gather_weights_sum_to_one(scene, mis, device):
    o = gather_sums(scene, {"gather.suffixes": 4, "gather.mis": mis}, device=device)
    err = np.abs(o[:, 1] - 1)
    print(f"{scene} {mis}: {len(o)} suffixes; produced by a neighbour too: {np.mean(o[:, 2] > 0):.1%}; slots with "
          f"an empty reservoir: {o[:, 3].sum():.0f}; max |sum - 1| {err.max():.2e}")
    assert len(o) > 300 and np.mean(o[:, 2] > 0) > 0.3
    assert np.mean(err > TOL) <= 0.002


def test_dropping_empty_slots_breaks_the_partition_of_unity():
    o = gather_sums("builtin:indirect-room", {"gather.suffixes": 4}, "drop_empty_slots")
    with_empty = o[o[:, 3] > 0]
    bad = np.mean(np.abs(with_empty[:, 1] - 1) > TOL)
    print(f"drop_empty_slots: {len(with_empty)} suffixes with an empty slot; weights off for {bad:.1%}")
    assert len(with_empty) > 50 and bad > 0.2
