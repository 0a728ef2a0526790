"""ReSTIR PT shifts, deterministic properties (D2, D3 of
docs/validation.md#level-0-deterministic-property-tests;
docs/theory/restir_pt.md#the-hybrid-shift), on the base
paths of real scenes, calling the production shift (path_reuse/shift.py) from a test kernel:

- identity (D2): a path shifted into its own domain is itself (F within 1e-3 relative) with J = 1;
- round trip (D3): a path shifted to another pixel and back is the source path again (F within
  1e-3 relative), J(src -> dst) J(dst -> src) = 1 within 1e-3, and a shift succeeds iff the
  inverse of its result does.
At most 0.2% outliers are allowed (grazing reconnections in float32), and every shift kind must
actually succeed on a good share of the pixel pairs (a test of dead shifts is no test).
"""
import numpy as np
import pytest

import restir
from tests.unit.shift_harness import assert_identity_and_round_trip, base_paths, run_round_trips


def round_trips(scene_spec, shift, direct="restir-di", offset=3, size=48, mutation="none", **kw):
    scene = restir.load_scene(scene_spec, width=size, height=size)
    integ, res, gb = base_paths(scene, shift, direct, **kw)
    return run_round_trips(integ, integ.params(0, 0), gb, res, offset, mutation)


SCENES = ["builtin:cornell-box", pytest.param("builtin:cornell-box-glossy", marks=pytest.mark.slow),
          "builtin:indirect-room"]


@pytest.mark.gpu
@pytest.mark.parametrize("direct", ["restir-di", "pt"])
@pytest.mark.parametrize("shift", ["hybrid", "reconnection", "replay"])
@pytest.mark.parametrize("scene", SCENES)
def test_identity_and_round_trip(scene, shift, direct, device):
    check_identity_and_round_trip(scene, shift, direct, device=device)


def check_identity_and_round_trip(scene, shift, direct, mutation="none", device="cpu"):
    assert_identity_and_round_trip(round_trips(scene, shift, direct, mutation=mutation, device=device), shift,
                                   f"{scene} {shift} {direct}")


# (mutation, shift): each mutant shift must fail the identity / round-trip properties above. (An
# inverted J keeps J J^-1 = 1 and skipped destination criteria keep round trips valid: those two
# are caught by the integral test, test_pt_shift_integrals.py.)
ROUND_TRIP_MUTANTS = [("misaligned_replay", "replay"), ("misaligned_replay", "hybrid"),
                      ("keep_source_jacobian", "reconnection"), ("bsdf_twice", "reconnection")]


@pytest.mark.parametrize("mutation,shift", ROUND_TRIP_MUTANTS)
def test_mutant_shifts_break_identity_or_round_trip(mutation, shift):
    with pytest.raises(AssertionError):
        check_identity_and_round_trip("builtin:indirect-room", shift, "pt", mutation)


@pytest.mark.parametrize("shift", ["hybrid", "replay"])
def test_inlined_shift_is_the_shift_bit_for_bit(shift):
    """The shift's two builds (path_reuse/shift.py: out of line, and SHIFT_INLINED, which the
    temporal and spatial passes call) compute the same numbers: the round-trip kernel over each,
    on the same paths and pixel pairs, bit for bit (identity, forward and back shifts, J)."""
    scene = restir.load_scene("builtin:indirect-room", width=32, height=32)
    integ, res, gb = base_paths(scene, shift, "pt")
    out = run_round_trips(integ, integ.params(0, 0), gb, res)
    inlined = run_round_trips(integ, integ.params(0, 0), gb, res, inlined=True)
    assert out[:, 6].sum() > 100  # forward shifts that succeed
    assert np.array_equal(out, inlined)


@pytest.mark.parametrize("shift", ["hybrid", "reconnection", "replay"])
@pytest.mark.parametrize("scene", ["delta-lights", "thinlens"])
def test_identity_and_round_trip_with_delta_lights_and_a_lens(scene, shift):
    """The same properties on paths that end on point, spot and directional lights (mixed with an
    area light and an environment), and on primary hits through a thin lens
    (tests/data/feature_scene.py); a good share of the paths must end with NEE on a delta light."""
    from restir.integrators.path_reuse.path_sample import PATH_NONE
    from tests.scenes import feature_scene_named

    s = feature_scene_named(scene)
    s.camera.width = s.camera.height = 48
    integ, res, gb = base_paths(s, shift, "pt")
    flags = res.numpy()["flags"]
    delta_ends = (flags != PATH_NONE) & ((flags >> 22) & 1 == 1) & ((flags >> 27) & 1 == 1)
    print(scene, "paths ending with NEE on a delta light:", delta_ends.sum(), "of", (flags != PATH_NONE).sum())
    assert delta_ends.sum() > 200
    assert_identity_and_round_trip(run_round_trips(integ, integ.params(0, 0), gb, res), shift, f"{scene} {shift}")
