"""ReSTIR PT shifts, deterministic properties (TESTING.md D2, D3; ALGORITHMS.md 3), on the base
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
import warp as wp

import restir
from restir.api import make_integrator
from restir.integrators.common.gbuffer import GBuffer
from restir.integrators.common.shading import load_shading
from restir.integrators.path_reuse.domain import domain_at
from restir.integrators.path_reuse.params import PathReuseParams
from restir.integrators.path_reuse.path_sample import PathReservoir, holds_path, rc_length
from restir.integrators.path_reuse.shift import make_shift, shift_path
from restir.device.scene_device import SceneDevice


_kernels = {}


def round_trip_kernel(mutation: str = "none"):
    """The test kernel over the shipped shift, or over a mutant's (TESTING.md 5.11)."""
    if mutation not in _kernels:
        _kernels[mutation] = make_round_trip_kernel(shift_path if mutation == "none" else make_shift(mutation))
    return _kernels[mutation]


def make_round_trip_kernel(shift_path):
    @wp.kernel(module="unique")
    def round_trip_kernel(scene: SceneDevice, params: PathReuseParams, gb: GBuffer, reservoirs: wp.array(dtype=PathReservoir),
                            partner: wp.array(dtype=int), out: wp.array2d(dtype=float)):
        """Per pixel: [holds, rc length, F lum, identity valid, identity F lum, identity J, forward valid,
        back valid, back F lum, J product, forward J]."""
        pixel = wp.tid()
        r = reservoirs[pixel]
        for i in range(11):
            out[pixel, i] = 0.0
        sc = load_shading(scene, gb, pixel)
        if not holds_path(r) or sc.valid == 0 or r.W <= 0.0:
            return
        out[pixel, 0] = 1.0
        out[pixel, 1] = float(rc_length(r.flags))
        out[pixel, 2] = wp.dot(r.F, wp.vec3(0.2126, 0.7152, 0.0722))
        idn = shift_path(scene, r, domain_at(sc, params))
        out[pixel, 3] = float(idn.valid)
        out[pixel, 4] = wp.dot(idn.r.F, wp.vec3(0.2126, 0.7152, 0.0722))
        out[pixel, 5] = idn.J
        n = partner[pixel]
        sn = load_shading(scene, gb, n)
        fwd = shift_path(scene, r, domain_at(sn, params))
        out[pixel, 6] = float(fwd.valid)
        if fwd.valid != 0:
            back = shift_path(scene, fwd.r, domain_at(sc, params))
            out[pixel, 7] = float(back.valid)
            out[pixel, 8] = wp.dot(back.r.F, wp.vec3(0.2126, 0.7152, 0.0722))
            out[pixel, 9] = fwd.J * back.J
            out[pixel, 10] = fwd.J
    return round_trip_kernel


def base_paths(scene, shift, direct="restir-di", max_depth=5):
    cfg = restir.RenderConfig(method="restir-pt", spp=1, frames=1, seed=7,
                              max_depth=max_depth,
                              settings={"shift": shift, "direct": direct, "temporal": False, "spatial.rounds": 0})
    integ = make_integrator(scene, cfg)
    integ.render_frame(0)
    # after the frame, the final reservoirs and G-buffer are the "previous" ones
    return integ, integ.reservoirs.previous, integ.gbuffers.previous


def round_trips(scene_spec, shift, direct="restir-di", offset=3, size=48, mutation="none", **kw):
    scene = restir.load_scene(scene_spec, width=size, height=size)
    integ, res, gb = base_paths(scene, shift, direct, **kw)
    return run_round_trips(integ, integ.params(0, 0), gb, res, offset, mutation)


def run_round_trips(integ, p, gb, res, offset=3, mutation="none"):
    """The round-trip kernel over every pixel of `integ` with partner pixel (x + offset, y):
    domains from the G-buffer `gb` (primary hits; for suffixes, the prefix ends), paths `res`."""
    n = integ.num_pixels
    w = integ.width
    idx = np.arange(n)
    x, y = idx % w, idx // w
    partner = (y * w + np.where(x + offset < w, x + offset, x - offset)).astype(np.int32)
    out = wp.zeros((n, 11), dtype=float, device=integ.device)
    wp.launch(round_trip_kernel(mutation), dim=n, inputs=[integ.dscene.scene, p, gb, res,
                                                 wp.array(partner, dtype=int, device=integ.device), out],
              device=integ.device)
    return out.numpy()


def rel(a, b):
    return np.abs(a - b) / np.maximum(np.abs(b), 1e-30)


SCENES = ["builtin:cornell-box", pytest.param("builtin:cornell-box-glossy", marks=pytest.mark.slow),
          "builtin:indirect-room"]


@pytest.mark.parametrize("direct", ["restir-di", "pt"])
@pytest.mark.parametrize("shift", ["hybrid", "reconnection", "replay"])
@pytest.mark.parametrize("scene", SCENES)
def test_identity_and_round_trip(scene, shift, direct):
    check_identity_and_round_trip(scene, shift, direct)


def check_identity_and_round_trip(scene, shift, direct, mutation="none"):
    assert_identity_and_round_trip(round_trips(scene, shift, direct, mutation=mutation), shift,
                                   f"{scene} {shift} {direct}")


def assert_identity_and_round_trip(o, shift, label, min_success=0.2):
    """D2 and D3 on the round-trip kernel's output (at most 0.2% failures each); forward shifts
    must succeed for at least `min_success` of the paths."""
    holds = o[:, 0] > 0
    assert holds.sum() > 200, "too few pixels hold a path"
    # D2: identity
    ident = o[holds]
    bad_valid = ident[:, 3] == 0
    bad = bad_valid | (rel(ident[:, 4], ident[:, 2]) > 1e-3) | (np.abs(ident[:, 5] - 1) > 1e-3)
    print(label, "paths", holds.sum(), "identity failures", bad.sum(),
          "rc lengths", np.unique(ident[:, 1], return_counts=True))
    assert bad.sum() <= max(1, 0.002 * holds.sum())
    # D3: round trips of successful forward shifts
    fwd = ident[:, 6] > 0
    assert fwd.mean() > min_success, f"shift success rate {fwd.mean():.3f}: reuse nearly dead"
    t = ident[fwd]
    bad = (t[:, 7] == 0) | (rel(t[:, 8], t[:, 2]) > 1e-3) | (np.abs(t[:, 9] - 1) > 1e-3)
    print("forward success", fwd.mean(), "round-trip failures", bad.sum(), "of", fwd.sum(),
          "J range", t[:, 10].min(), t[:, 10].max())
    assert bad.sum() <= max(1, 0.002 * fwd.sum())
    if shift == "replay":
        np.testing.assert_array_equal(t[:, 10], 1.0)
    else:
        assert np.std(np.log(t[:, 10])) > 1e-3, "reconnection Jacobians are all 1: not exercised"


# (mutation, shift): each mutant shift must fail the identity / round-trip properties above. (An
# inverted J keeps J J^-1 = 1 and skipped destination criteria keep round trips valid: those two
# are caught by the integral test, test_pt_shift_integrals.py.)
ROUND_TRIP_MUTANTS = [("misaligned_replay", "replay"), ("misaligned_replay", "hybrid"),
                      ("keep_source_jacobian", "reconnection"), ("bsdf_twice", "reconnection")]


@pytest.mark.parametrize("mutation,shift", ROUND_TRIP_MUTANTS)
def test_mutant_shifts_break_identity_or_round_trip(mutation, shift):
    with pytest.raises(AssertionError):
        check_identity_and_round_trip("builtin:indirect-room", shift, "pt", mutation)
