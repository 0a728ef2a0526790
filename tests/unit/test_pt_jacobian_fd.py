"""D5 (docs/validation.md#level-0-deterministic-property-tests): the shifts' analytic Jacobians
against finite-difference Jacobians of the
shift in primary sample space (PSS), on the base paths of real scenes.

A path with a reconnection (rc) vertex z reaches z from rcPrev x_{r-1} with the numbers
(u_lobe, u) of bounce r-1, and (when z scatters on) leaves z toward the fixed direction w_o with
the numbers of bounce r. Shifted to the destination, the replayed prefix (bounces 0..r-2, the
same numbers: the identity in PSS) reaches y_{r-1}; the numbers that would sample y_{r-1} -> z
and, at z under its new incoming direction, w_o, are the destination's coordinates u'. Since u'
of bounce r-1 does not depend on the numbers of bounce r, the PSS Jacobian is the product of two
blocks, each taken here by central differences:

- at rcPrev: u -> z(u) (the production sampler at x_{r-1} and a traced ray) -> u' = S^-1 at
  y_{r-1} of the direction to z (for the environment: of the same direction);
- at z, when z scatters on: u -> w_o(u) (the production sampler at z with the source's incoming
  direction) -> u' = S^-1 at z with the destination's incoming direction;

each times the ratio of the lobe's selection probabilities (the length of the u_lobe interval
that picks the lobe, found by bisection on the production sampler). S^-1 is the inverse of the
lobe's direction sampler (restir.device: cosine_hemisphere_to_square,
microfacet_sample_to_square; their round trips are tested below). Nothing of J's formula is
used: the test sees only the samplers, ray tracing and the production shift's returned J, whose
source terms are those the base path cached. Pure replay moves no vertex by reconnection: its
PSS Jacobian is exactly 1 (u' = u); test_pt_shifts.py asserts that the shift returns exactly 1.

Cases covered (printed per scene): rc vertex at x2 and deeper (1-3 replayed bounces), diffuse,
GGX and Beckmann rcPrev and z, the rough-plastic lobes (whose selection probability depends on
the incoming direction), NEE at z, emission found from z, z an emitter, z the environment.
Pixels where a perturbed ray hits another triangle or picks another lobe are skipped.
Tolerances (float32, h = 1e-3): median relative error < 1e-3, 99th percentile < 1e-2. The
mutants that drop the pdf ratio at z or invert J must fail them.
"""
import numpy as np
import pytest
import warp as wp

import restir
from restir.api import make_integrator
from restir.device.microfacet import Microfacet, microfacet_sample, microfacet_sample_to_square
from restir.device.sampling import cosine_hemisphere_to_square, square_to_cosine_hemisphere
from restir.device.types import MICROFACET_BECKMANN, MICROFACET_GGX
from restir.scene.builtin import cornell_box
from tests.scenes import feature_scene_named
from tests.shared_scenes import scene_path
from tests.unit.shift_harness import J_RANGE, describe, relative_errors, run_fd, well_conditioned

# z error, the smallest |cos| at the ends of the two reconnection segments]


def open_box(**kw):
    """The glossy Cornell box without its back wall and ceiling, under a constant sky: paths
    escape to the environment (rc vertex: the environment) and find the light (z: the emitter)."""
    scene = cornell_box(glossy=True, light_scale=3.0, **kw)
    del scene["back"], scene["ceiling"]
    scene["sky"] = {"type": "constant", "radiance": {"type": "rgb", "value": [0.4, 0.5, 0.7]}}
    return scene


SIZE = 128
SCENES = {
    "cornell-box": lambda: restir.load_scene("builtin:cornell-box"),
    "cornell-box-glossy": lambda: restir.load_scene("builtin:cornell-box-glossy"),
    "indirect-room": lambda: restir.load_scene("builtin:indirect-room"),
    "open-box": lambda: restir.load_scene(open_box()),
    "veach-bidir": lambda: restir.load_scene(str(scene_path("veach-bidir"))),
    # point, spot and directional lights with an area light and an environment: paths whose NEE
    # end at z connects to a delta light (tests/data/feature_scene.py)
    "delta-lights": lambda: feature_scene_named("delta-lights"),
}


def fd_jacobians(name, shift, mutation="none", offset=(5, 3), device="cpu"):
    scene = SCENES[name]()
    scene.camera.width = scene.camera.height = SIZE
    cfg = restir.RenderConfig(method="restir-pt", spp=1, max_depth=6, seed=5, device=device,
                              settings={"shift": shift, "direct": "pt", "temporal": False, "spatial.rounds": 0})
    integ = make_integrator(scene, cfg)
    integ.render_frame(0)
    return run_fd(integ, integ.params(0, 0), integ.gbuffers.previous, integ.reservoirs.previous, mutation, offset)


CASES = [("cornell-box", "reconnection"), ("cornell-box-glossy", "reconnection"), ("cornell-box-glossy", "hybrid"),
         ("indirect-room", "hybrid"), ("indirect-room", "reconnection"), ("open-box", "hybrid"),
         ("veach-bidir", "hybrid"), ("delta-lights", "reconnection"), ("delta-lights", "hybrid")]


@pytest.mark.gpu
@pytest.mark.parametrize("name,shift", CASES)
def test_shift_jacobian_matches_finite_differences(name, shift, device):
    shifted = fd_jacobians(name, shift, device=device)
    o = well_conditioned(shifted)
    rel = relative_errors(o)
    print(describe(name, shift, o, rel), f"; grazing or J outside {J_RANGE} (left out): {len(shifted) - len(o)}")
    assert len(o) > 300
    assert np.max(o[:, 8]) < 1e-3  # the sampled rcPrev bounce reaches the recorded z
    assert np.std(np.log(o[:, 1])) > 0.1  # the Jacobians vary: the test is not about J = 1
    assert np.median(rel) < 1e-3 and np.percentile(rel, 99) < 1e-2
    # (veach-bidir's hybrid paths replay rarely: 5 of 2272; the delta-light room's rough surfaces never
    # make rcPrev anything but the primary hit)
    if shift == "hybrid" and name not in ("veach-bidir", "delta-lights"):
        assert (o[:, 3] >= 2).sum() > 20  # paths with replayed bounces before rcPrev
    if name in ("cornell-box-glossy", "indirect-room"):
        glossy_z = (o[:, 5] > 0) & (o[:, 6] != 0)  # z scatters on, and is not plain diffuse
        assert glossy_z.sum() > 50
    if name == "open-box":
        assert (o[:, 4] == 1).sum() > 20 and (o[:, 4] == 2).sum() > 20  # z an emitter, z the environment


@pytest.mark.parametrize("mutation", ["drop_rc_pdf", "invert_jacobian"])
def test_jacobian_mutants_fail_finite_differences(mutation):
    """docs/validation.md#power-checks-the-mutation-table: J without the pdf ratio at z, and 1/J,
    disagree with the finite differences
    on the paths they change (glossy z for the first)."""
    o = well_conditioned(fd_jacobians("indirect-room", "hybrid", mutation))
    rel = relative_errors(o)
    print(describe("indirect-room", f"hybrid ({mutation})", o, rel))
    assert np.percentile(rel, 99) > 0.1 and (rel > 0.05).mean() > 0.05


@wp.kernel
def warp_round_trip_kernel(kind: int, alpha: wp.vec2, wi: wp.array(dtype=wp.vec3), u: wp.array(dtype=wp.vec2),
                           out: wp.array(dtype=wp.vec2)):
    i = wp.tid()
    if kind < 0:
        out[i] = cosine_hemisphere_to_square(square_to_cosine_hemisphere(u[i]))
        return
    d = Microfacet()
    d.kind = kind
    d.alpha_u = alpha[0]
    d.alpha_v = alpha[1]
    out[i] = microfacet_sample_to_square(d, wi[i], microfacet_sample(d, wi[i], u[i]))


@pytest.mark.parametrize("kind,alpha", [(-1, (1.0, 1.0)), (MICROFACET_GGX, (0.3, 0.3)), (MICROFACET_GGX, (0.05, 0.6)),
                                        (MICROFACET_BECKMANN, (0.4, 0.4)), (MICROFACET_BECKMANN, (0.1, 0.5))])
def test_inverse_samplers_round_trip(kind, alpha):
    """S^-1(S(u)) = u for the inverse direction samplers the finite differences rely on."""
    rng = np.random.default_rng(1)
    n = 20000
    u = rng.uniform(0.01, 0.99, (n, 2)).astype(np.float32)
    wi = rng.normal(size=(n, 3))
    wi[:, 2] = np.abs(wi[:, 2]) + 0.05
    wi = (wi / np.linalg.norm(wi, axis=1, keepdims=True)).astype(np.float32)
    wi[:100] = [0.0, 0.0, 1.0]  # normal incidence (the Beckmann sampler's special case)
    out = wp.zeros(n, dtype=wp.vec2, device="cpu")
    wp.launch(warp_round_trip_kernel, dim=n, device="cpu",
              inputs=[int(kind), wp.vec2(*alpha), wp.array(wi, dtype=wp.vec3, device="cpu"),
                      wp.array(u, dtype=wp.vec2, device="cpu"), out])
    d = np.abs(out.numpy() - u)
    d = np.minimum(d, 1.0 - d)  # the angle coordinate wraps around
    print(f"kind {kind} alpha {alpha}: max |S^-1(S(u)) - u| = {d.max():.2e}, 99.9th percentile "
          f"{np.percentile(d, 99.9):.2e}")
    assert np.percentile(d, 99.9) < 1e-4
