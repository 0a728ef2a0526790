"""D1 at stage level (docs/validation.md#level-0-deterministic-property-tests): the MIS weights
ReSTIR PT's reuse passes give one path y
sum to 1 over every technique that can produce it, with real shifts on the base paths of real
scenes, computed by the passes' own functions (reuse_pair.py's shifts and densities, the
pairwise accumulator and the Talbot weight of resampling/mis.py).

For a pixel c whose sample is y, and techniques chosen by geometry only (k neighbours at fixed
offsets, kept when their primary hit is similar, as the spatial pass keeps them; or one "history"
pixel for the temporal pass), technique j can produce y from x_j = T_{c->j}(y) when that shift
succeeds. Its weight at y is the one the pass gives x_j after shifting it back into c (shift_in),
and the canonical weight is the one the pass gives y from y's shifts to the techniques
(shift_out). Spatial (pairwise): (m_c + sum_j m_j) / (V + 1) = 1; temporal (Talbot, the history's
confidence capped as the pass caps it): m_current + m_history = 1. Confidences differ per
technique, so an M used inconsistently between the two directions shows. Up to 0.2% of paths may
miss by more than 1e-4 (float32 round trips at grazing reconnections, as D3 allows).
"""
import numpy as np
import pytest
import warp as wp

import restir
from restir.api import make_integrator
from restir.device.color import luminance
from restir.device.scene_device import SceneDevice
from restir.integrators.common.gbuffer import GBuffer
from restir.integrators.common.shading import load_shading, similar_surfaces
from restir.integrators.path_reuse.domain import domain_at
from restir.integrators.path_reuse.params import PathReuseParams
from restir.integrators.path_reuse.path_sample import PathReservoir, holds_path
from restir.integrators.path_reuse.reuse_pair import make_reuse_pair
from restir.integrators.path_reuse.reuse_pair import CURRENT, HISTORY
from restir.integrators.path_reuse.shift import make_shift, shift_path
from restir.resampling.mis import pairwise_add_neighbor, pairwise_init, pairwise_normalization, talbot_weight2
from restir.resampling.ris import cap_history

K = 3


@wp.func
def neighbor_offset(j: int) -> wp.vec2i:
    if j == 0:
        return wp.vec2i(4, 0)
    if j == 1:
        return wp.vec2i(0, 3)
    return wp.vec2i(-3, -2)


@wp.func
def with_confidence(r: PathReservoir, M: float) -> PathReservoir:
    """r as a technique's input with confidence M (and some W > 0: the weights do not read it)."""
    out = r
    out.M = M
    out.W = 1.0
    return out
TOL = 1e-4  # measured: |sum - 1| <= 1.9e-6 on every path of the six configurations
N_OUT = 5  # [tested, spatial sum, neighbours producing y, temporal sum, history produces y]


def make_mis_kernel(shift):
    shift_in, shift_out, _, _ = make_reuse_pair(shift, None if shift is shift_path else "unique")

    @wp.kernel(module="unique")
    def mis_kernel(scene: SceneDevice, params: PathReuseParams, gb: GBuffer, reservoirs: wp.array(dtype=PathReservoir),
                   width: int, height: int, history_cap: float, out: wp.array2d(dtype=float)):
        pixel = wp.tid()
        for col in range(N_OUT):
            out[pixel, col] = 0.0
        sc = load_shading(scene, gb, pixel)
        if sc.valid == 0 or not holds_path(reservoirs[pixel]) or reservoirs[pixel].W <= 0.0:
            return
        M_c = 1.0 + float(pixel % 3)  # confidences that differ per technique
        c = with_confidence(reservoirs[pixel], M_c)
        p_c = luminance(c.F)
        px = pixel % width
        py = pixel // width
        # ---- spatial: pairwise over k neighbours valid by geometry
        acc = pairwise_init(K)
        m_neighbors = float(0.0)
        producing = int(0)
        for j in range(K):
            nx = px + neighbor_offset(j)[0]
            ny = py + neighbor_offset(j)[1]
            if nx < 0 or ny < 0 or nx >= width or ny >= height:
                continue
            sn = load_shading(scene, gb, ny * width + nx)
            if sn.valid == 0 or not similar_surfaces(sc, sn):
                continue
            M_j = 0.5 + float(j)
            own = shift_out(scene, c, M_j, domain_at(sn, params))  # y in technique j's domain: x_j
            d_j_at_y = float(0.0)
            d_c_at_y = float(0.0)
            if own.t.valid != 0:
                # as the pass shifts x_j here
                back = shift_in(scene, with_confidence(own.t.r, M_j), M_j, M_c, domain_at(sc, params))
                d_j_at_y = back.d_i
                d_c_at_y = back.d_c
                producing += 1
            acc = pairwise_add_neighbor(acc, d_j_at_y, d_c_at_y, p_c * M_c, own.d_i)
            m_neighbors += acc.m_i
        out[pixel, 0] = 1.0
        out[pixel, 1] = (acc.m_c + m_neighbors) / pairwise_normalization(acc)
        out[pixel, 2] = float(producing)
        # ---- temporal: Talbot over the current sample and a history pixel (capped confidence)
        hq = (py + 2) % height * width + (px + 3) % width
        sq = load_shading(scene, gb, hq)
        if sq.valid == 0 or not similar_surfaces(sc, sq):
            out[pixel, 3] = 1.0  # one technique: m_current = 1
            return
        M_q = cap_history(7.0, history_cap, M_c)
        cur = shift_out(scene, c, M_q, domain_at(sq, params))
        m_total = talbot_weight2(p_c * M_c, cur.d_i, CURRENT)
        if cur.t.valid != 0:
            hist = shift_in(scene, with_confidence(cur.t.r, M_q), M_q, M_c, domain_at(sc, params))
            m_total += talbot_weight2(hist.d_c, hist.d_i, HISTORY)
            out[pixel, 4] = 1.0
        out[pixel, 3] = m_total

    return mis_kernel


_kernels = {}


def mis_sums(scene_spec, shift, mutation="none", size=64, device="cpu"):
    if mutation not in _kernels:
        _kernels[mutation] = make_mis_kernel(shift_path if mutation == "none" else make_shift(mutation))
    scene = restir.load_scene(scene_spec, width=size, height=size)
    cfg = restir.RenderConfig(method="restir-pt", spp=1, max_depth=5, seed=11, device=device,
                              settings={"shift": shift, "direct": "pt", "temporal": False, "spatial.rounds": 0})
    integ = make_integrator(scene, cfg)
    integ.render_frame(0)
    out = wp.zeros((integ.num_pixels, N_OUT), dtype=float, device=integ.device)
    wp.launch(_kernels[mutation], dim=integ.num_pixels, device=integ.device,
              inputs=[integ.dscene.scene, integ.params(0, 0), integ.gbuffers.previous, integ.reservoirs.previous,
                      integ.width, integ.height, 2.0, out])
    o = out.numpy()
    return o[o[:, 0] > 0]


def bad_fraction(o):
    return float(np.mean(np.abs(o[:, 1] - 1) > TOL)), float(np.mean(np.abs(o[:, 3] - 1) > TOL))


@pytest.mark.gpu
@pytest.mark.parametrize("shift", ["hybrid", "reconnection", "replay"])
@pytest.mark.parametrize("scene", ["builtin:indirect-room", "builtin:cornell-box-glossy"])
def test_reuse_mis_weights_sum_to_one(scene, shift, device):
    o = mis_sums(scene, shift, device=device)
    spatial_bad, temporal_bad = bad_fraction(o)
    print(f"{scene} {shift}: {len(o)} paths; spatial: {np.mean(o[:, 2] > 0):.1%} produced by a neighbour too, "
          f"sum off by > {TOL} for {spatial_bad:.3%} (max |sum - 1| {np.max(np.abs(o[:, 1] - 1)):.2e}); temporal: "
          f"{np.mean(o[:, 4]):.1%} produced by the history too, off for {temporal_bad:.3%}")
    assert len(o) > 1000
    assert np.mean(o[:, 2] > 0) > 0.2 and np.mean(o[:, 4]) > 0.2  # the neighbours' weights are exercised
    assert spatial_bad <= 0.002 and temporal_bad <= 0.002


@pytest.mark.parametrize("mutation,shift", [("keep_source_jacobian", "reconnection"), ("misaligned_replay", "replay")])
def test_mutant_shifts_break_the_partition_of_unity(mutation, shift):
    """Power check: a cached Jacobian left at the source's values, or a replay reading the next
    bounce's numbers, make the two directions of a pair disagree, and the weights stop summing to 1."""
    spatial_bad, temporal_bad = bad_fraction(mis_sums("builtin:indirect-room", shift, mutation))
    print(mutation, shift, f"off by > {TOL}: spatial {spatial_bad:.1%}, temporal {temporal_bad:.1%}")
    assert spatial_bad > 0.05 and temporal_bad > 0.05
