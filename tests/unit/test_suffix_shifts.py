"""Suffix ReSTIR's suffix shifts (docs/guide/suffix_restir.md): ReSTIR PT's shift with the prefix end
as start vertex, on the suffixes Suffix ReSTIR traces at its prefix ends, between the prefix
ends of two pixels: D2 (identity), D3 (round trip, J J' = 1) and D5 (J against finite
differences in primary sample space), with the harnesses of the ReSTIR PT tests. The suffix
domains' length budgets are those of the shortest prefix (max_depth - 1): every shift is tried.
"""
import numpy as np
import pytest

import restir
from restir.api import make_integrator
from restir.integrators.suffix_restir.domains import suffix_params
from tests.unit.shift_harness import (assert_identity_and_round_trip, describe, relative_errors, run_fd, run_round_trips,
                                     well_conditioned)


def suffixes(scene_spec, shift, size, direct="pt", max_depth=6, device="cpu", **settings):
    """One frame without reuse: each pixel's suffix at its prefix end; (integrator, params, prefix
    G-buffer, suffix reservoirs)."""
    scene = restir.load_scene(scene_spec)
    scene.camera.width = scene.camera.height = size
    cfg = restir.RenderConfig(method="suffix-restir", spp=1, frames=1, seed=7, max_depth=max_depth, device=device,
                              settings={"shift": shift, "direct": direct, "prefix.temporal": False,
                                        "suffix.temporal": False, "suffix.spatial.rounds": 0, **settings})
    integ = make_integrator(scene, cfg)
    integ.render_frame(0)
    p = suffix_params(integ.params(0, 0), 1)
    return integ, p, integ.prefix_gbs.previous, integ.reservoirs.previous


@pytest.mark.gpu
@pytest.mark.parametrize("shift", ["hybrid", "reconnection", "replay"])
@pytest.mark.parametrize("scene", ["builtin:indirect-room", "builtin:cornell-box-glossy"])
def test_suffix_identity_and_round_trip(scene, shift, device):
    integ, p, gb, res = suffixes(scene, shift, 48, device=device)
    # pixels 3 px apart have unrelated prefix ends (random first bounces): fewer shifts succeed
    assert_identity_and_round_trip(run_round_trips(integ, p, gb, res), shift, f"suffixes {scene} {shift}",
                                   min_success=0.1)


@pytest.mark.gpu
@pytest.mark.parametrize("shift", ["hybrid", "reconnection"])
def test_suffix_jacobian_matches_finite_differences(shift, device):
    integ, p, gb, res = suffixes("builtin:cornell-box-glossy", shift, 96, device=device)
    o = well_conditioned(run_fd(integ, p, gb, res))
    rel = relative_errors(o)
    print(describe("suffixes, glossy Cornell box", shift, o, rel))
    assert len(o) > 300 and np.std(np.log(o[:, 1])) > 0.1
    assert np.median(rel) < 1e-3 and np.percentile(rel, 99) < 1e-2


@pytest.mark.parametrize("mutation", ["rc_index_at_prefix_length", "suffix_seed_not_reset", "prefix_thp_in_target"])
def test_suffix_mutants_break_identity(mutation):
    """docs/validation.md#power-checks-the-mutation-table: the rc index recorded at the prefix
    length (prefixes ending at x3, so that
    it differs from the suffix's own index), the replay seed not restarted at the prefix end, and
    the prefix's throughput in the suffix's target each make the identity shift fail."""
    integ, p, gb, res = suffixes("builtin:cornell-box-glossy", "hybrid", 48,
                                 **{"prefix.min_length": 2, "debug.mutation": mutation})
    with pytest.raises(AssertionError):
        assert_identity_and_round_trip(run_round_trips(integ, p, gb, res), "hybrid", mutation, min_success=0.1)
