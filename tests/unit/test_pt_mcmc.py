"""ReSTIR PT's MCMC suffix mutation (restir_pt/s3_mcmc.py, path_reuse/suffix_mutation.py),
deterministic properties on the base paths of real scenes (the estimator's unbiasedness is the
statistical tests' job: test_restir_pt.py, the slow matrix):

- the proposal follows the base path tracer: proposed with the sample's own seed in its own
  pixel, it rebuilds exactly the suffix the base path cached (z's direction, radiance, pdfs,
  lobe), for every end type and rc length;
- a mutated sample is a valid sample of its pixel: shifted into its own domain it reproduces its
  F with J = 1, and it survives round trips to other pixels (D2, D3);
- a step changes only what it should: the suffix fields, F and W, with p_hat W kept, never the
  seed, z, the prefix's Jacobian terms, the lengths or M; and it does change a good share.
"""
import numpy as np
import pytest
import warp as wp

import restir
from restir.api import make_integrator
from restir.device.color import luminance
from restir.device.scene_device import SceneDevice
from restir.integrators.common.gbuffer import GBuffer
from restir.integrators.common.shading import load_shading
from restir.integrators.path_reuse.params import PathReuseParams
from restir.integrators.path_reuse.path_sample import PathReservoir, rc_length
from restir.integrators.path_reuse.shift import replay_prefix
from restir.integrators.path_reuse.suffix_mutation import mutable, propose_suffix
from tests.unit.shift_harness import assert_identity_and_round_trip, run_round_trips

BASE = {"temporal": False, "spatial.rounds": 0}


def first_frame(scene_spec, settings, size=48, max_depth=5, seed=7):
    """One frame of ReSTIR PT without reuse (the pixels' own base paths, mutated where
    mcmc.steps > 0); its final reservoirs and G-buffer (the "previous" ones after the frame)."""
    scene = restir.load_scene(scene_spec, width=size, height=size)
    cfg = restir.RenderConfig(method="restir-pt", spp=1, frames=1, seed=seed, max_depth=max_depth,
                              settings={**BASE, **settings})
    integ = make_integrator(scene, cfg)
    integ.render_frame(0)
    return integ, integ.reservoirs.previous, integ.gbuffers.previous


@wp.kernel(module="unique")
def own_seed_proposal_kernel(scene: SceneDevice, params: PathReuseParams, gb: GBuffer,
                             reservoirs: wp.array(dtype=PathReservoir), from_rc_prev: int, out: wp.array2d(dtype=float)):
    """Per pixel: [mutable, proposal valid, rc length, |rc_wi - stored|, rel. rc_L difference,
    rel. light_pdf difference, rel. rc_jac[1] difference, flags equal, z equal, rel. rc_jac[0]
    difference]."""
    pixel = wp.tid()
    for i in range(10):
        out[pixel, i] = 0.0
    r = reservoirs[pixel]
    sh = load_shading(scene, gb, pixel)
    if not mutable(r) or sh.valid == 0:
        return
    out[pixel, 0] = 1.0
    y = replay_prefix(scene, params, sh, r.seed, rc_length(r.flags) - 1)
    p = propose_suffix(scene, params, r, y, r.seed, from_rc_prev)
    out[pixel, 1] = float(p.valid)
    out[pixel, 2] = float(rc_length(r.flags))
    out[pixel, 3] = wp.length(p.r.rc_wi - r.rc_wi)
    out[pixel, 4] = wp.length(p.r.rc_L - r.rc_L) / wp.max(wp.length(r.rc_L), 1.0e-20)
    out[pixel, 5] = wp.abs(p.r.light_pdf - r.light_pdf) / wp.max(r.light_pdf, 1.0e-20)
    out[pixel, 6] = wp.abs(p.r.rc_jac[1] - r.rc_jac[1]) / wp.max(r.rc_jac[1], 1.0e-20)
    out[pixel, 7] = wp.where(p.r.flags == r.flags, 1.0, 0.0)
    out[pixel, 8] = wp.where(p.r.rc_tri == r.rc_tri and wp.length(p.r.rc_bary - r.rc_bary) < 1.0e-6, 1.0, 0.0)
    out[pixel, 9] = wp.abs(p.r.rc_jac[0] - r.rc_jac[0]) / wp.max(r.rc_jac[0], 1.0e-20)


SCENES = ["builtin:cornell-box-glossy", "builtin:indirect-room"]


@pytest.mark.parametrize("start", ["z", "rc_prev"])
@pytest.mark.parametrize("direct", ["restir-di", "pt"])
@pytest.mark.parametrize("shift", ["hybrid", "reconnection"])
@pytest.mark.parametrize("scene", SCENES)
def test_proposal_with_the_seeds_numbers_is_the_base_path(scene, shift, direct, start):
    integ, res, gb = first_frame(scene, {"shift": shift, "direct": direct})
    o = np.zeros((integ.num_pixels, 10), np.float32)
    out = wp.array(o, dtype=float, device=integ.device)
    wp.launch(own_seed_proposal_kernel, dim=integ.num_pixels,
              inputs=[integ.dscene.scene, integ.params(0, 0), gb, res, int(start == "rc_prev"), out],
              device=integ.device)
    o = out.numpy()
    m = o[:, 0] > 0
    print(scene, shift, direct, "mutable", m.sum(), "rc lengths", np.unique(o[m, 2], return_counts=True))
    assert m.sum() > 300
    if shift == "hybrid":
        assert (o[m, 2] > 1).any(), "no path with a replayed prefix: the test would not cover replay"
    bad = ((o[m, 1] == 0) | (o[m, 3] > 1e-5) | (o[m, 4] > 1e-4) | (o[m, 5] > 1e-4) | (o[m, 6] > 1e-4) | (o[m, 7] == 0)
           | (o[m, 8] == 0) | (o[m, 9] > 1e-4))
    assert bad.sum() <= 0.002 * m.sum(), o[m][bad][:5]


@pytest.mark.parametrize("start", ["z", "rc_prev"])
@pytest.mark.parametrize("shift", ["hybrid", "reconnection"])
@pytest.mark.parametrize("scene", SCENES)
def test_mutated_samples_shift_like_base_paths(scene, shift, start):
    integ, res, gb = first_frame(scene, {"shift": shift, "direct": "pt", "mcmc.steps": 2, "mcmc.start": start})
    assert integ.stats()["mcmc"]["accepted"] > 50
    o = run_round_trips(integ, integ.params(0, 0), gb, res, 3)
    assert_identity_and_round_trip(o, shift, f"{scene} {shift} mcmc.steps=2")


FIELDS = ("F", "W", "M", "flags", "seed", "rc_tri", "rc_bary", "rc_wi", "rc_L", "rc_jac", "light_pdf")


def reservoir_fields(res) -> dict:
    a = res.numpy()
    return {f: np.asarray(a[f]) for f in FIELDS}


@pytest.mark.parametrize("start", ["z", "rc_prev"])
def test_a_step_changes_the_suffix_and_keeps_the_rest(start):
    check_a_step({"direct": "pt", "mcmc.steps": 1, "mcmc.start": start})


def test_a_step_without_the_weight_update_is_caught():
    with pytest.raises(AssertionError):
        check_a_step({"direct": "pt", "mcmc.steps": 1, "debug.mutation": "mcmc_keep_w"})


def check_a_step(settings):
    before = reservoir_fields(first_frame("builtin:cornell-box-glossy", {"direct": "pt"})[1])
    integ, res, _ = first_frame("builtin:cornell-box-glossy", settings)
    after = reservoir_fields(res)
    rcl = (before["flags"] >> 8) & 255
    kind = (before["flags"] >> 23) & 3
    holds = before["flags"] != -1
    mut = holds & (rcl != 255) & (kind == 0)
    z_moves = settings.get("mcmc.start") == "rc_prev"
    for f in ("seed", "M") + (() if z_moves else ("rc_tri", "rc_bary")):
        np.testing.assert_array_equal(after[f], before[f], err_msg=f)
    # the lobe at z may change (and at rcPrev where z moves); lengths, end and kind may not
    lobe_mask = ~((7 << 19) | ((7 << 16) if z_moves else 0))
    np.testing.assert_array_equal(after["flags"] & lobe_mask, before["flags"] & lobe_mask)
    if not z_moves:
        np.testing.assert_array_equal(after["rc_jac"][:, 0], before["rc_jac"][:, 0])
    changed = np.any(after["rc_wi"] != before["rc_wi"], axis=1) | (after["rc_tri"] != before["rc_tri"])
    assert not changed[~mut].any(), "a sample without a surface rc vertex was mutated"
    stats = integ.stats()["mcmc"]
    print(stats, "changed", changed[mut].mean())
    assert changed.sum() == stats["accepted"]
    assert changed[mut].mean() > (0.1 if z_moves else 0.3)
    lum = np.array([0.2126, 0.7152, 0.0722], np.float32)
    c_before = (before["F"] @ lum) * before["W"]
    c_after = (after["F"] @ lum) * after["W"]
    np.testing.assert_allclose(c_after[holds], c_before[holds], rtol=1e-4, atol=0)


def test_mcmc_steps_are_checked():
    scene = restir.load_scene("builtin:cornell-box", width=8, height=8)
    with pytest.raises(restir.config.ConfigError, match="mcmc.steps"):
        restir.render(scene, method="restir-pt", spp=1, frames=1, settings={"mcmc.steps": 9})
