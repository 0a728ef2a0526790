"""ReSTIR PT shifts preserve integrals (the property every reuse pass relies on), tested on the
base paths of real scenes with the production shift (path_reuse/shift.py).

For pixels i and j = partner(i), with x_i the sample of i's initial reservoir (unbiased
contribution weight W_i) and T the shift i -> j with Jacobian J:

    E[ p_hat_j(T x_i) J W_i ]  =  integral of p_hat_j over T(domain of i)
                               =  E[ p_hat_j(x_j) W_j 1{T^-1 x_j valid} ]

(a shift is a bijection between the source paths it maps and the destination paths whose inverse
shift succeeds). Summed over all pixels of a frame, both sides are compared over independent
frames with a Welch z-test. A wrong J (inverted, or without z's pdf ratio), a BSDF applied twice,
destination criteria that are not checked (the two supports differ) or a replay that reads
other random numbers all break the equality; the test is run on the shipped shift and on each
of those mutants (docs/validation.md#power-checks-the-mutation-table), which must be caught.

False-failure rate: |z| > 4.4 per configuration, about 1e-5 for a normal statistic; a pass also
needs the minimum detectable bias (4.4 standard errors, relative) below 5%.
"""
import numpy as np
import pytest
import warp as wp

import restir
from restir.api import make_integrator
from restir.device.scene_device import SceneDevice
from restir.device.types import MAT_DIFFUSE
from restir.integrators.common.gbuffer import GBuffer
from restir.integrators.common.shading import load_shading
from restir.integrators.path_reuse.domain import domain_at
from restir.integrators.path_reuse.params import PathReuseParams
from restir.integrators.path_reuse.path_sample import (NO_RC, RC_SURFACE, PathReservoir, ends_with_nee, holds_path,
                                                      path_length, rc_kind, rc_length)
from restir.integrators.path_reuse.shift import make_shift, shift_path

Z_CRIT = 4.4
_kernels = {}


def integral_kernel(mutation: str):
    """Per pixel i: (a_i, b_i); a path counts only where its type matches `types` (a bit mask:
    1 = paths whose rc vertex z scatters, 2 = every other path), which the shift preserves."""
    if mutation in _kernels:
        return _kernels[mutation]
    shift = shift_path if mutation == "none" else make_shift(mutation)

    @wp.func
    def counted(r: PathReservoir, types: int) -> bool:
        rcl = rc_length(r.flags)
        z_scatters = rcl != NO_RC and rc_kind(r.flags) == RC_SURFACE and (
            path_length(r.flags) > rcl or ends_with_nee(r.flags) == 0)
        return (types & wp.where(z_scatters, 1, 2)) != 0

    @wp.func
    def lum(c: wp.vec3) -> float:
        return wp.dot(c, wp.vec3(0.2126, 0.7152, 0.0722))

    @wp.kernel(module="unique")
    def kernel(scene: SceneDevice, params: PathReuseParams, gb: GBuffer, reservoirs: wp.array(dtype=PathReservoir),
               partner: wp.array(dtype=int), types: int, diffuse_primaries: int, out: wp.array(dtype=wp.vec2)):
        i = wp.tid()
        j = partner[i]
        a = float(0.0)
        b = float(0.0)
        ri = reservoirs[i]
        si = load_shading(scene, gb, i)
        sj = load_shading(scene, gb, j)
        if si.valid != 0 and sj.valid != 0 and (diffuse_primaries == 0 or (
                si.mat.kind == MAT_DIFFUSE and sj.mat.kind == MAT_DIFFUSE)):
            if holds_path(ri) and ri.W > 0.0 and counted(ri, types):
                t = shift(scene, ri, domain_at(sj, params))
                if t.valid != 0:
                    a = lum(t.r.F) * t.J * ri.W
            rj = reservoirs[j]
            if holds_path(rj) and rj.W > 0.0 and counted(rj, types):
                back = shift(scene, rj, domain_at(si, params))
                if back.valid != 0:
                    b = lum(rj.F) * rj.W
        out[i] = wp.vec2(a, b)

    _kernels[mutation] = kernel
    return kernel


def shift_integrals(scene_spec, shift, mutation="none", frames=64, size=32, max_depth=5, offset=1, direct="pt",
                    types=3, diffuse_primaries=False, **scene_args):
    """Per frame: (sum_i a_i, sum_i b_i) as in the module docstring."""
    scene = restir.load_scene(scene_spec, width=size, height=size, **scene_args)
    cfg = restir.RenderConfig(method="restir-pt", spp=1, max_depth=max_depth, seed=11,
                              settings={"shift": shift, "direct": direct, "temporal": False, "spatial.rounds": 0})
    integ = make_integrator(scene, cfg)
    w, n = integ.width, integ.num_pixels
    idx = np.arange(n)
    x, y = idx % w, idx // w
    partner = wp.array((np.clip(y + offset, 0, w - 1) * w + np.where(x + offset < w, x + offset, x - offset)
                        ).astype(np.int32), dtype=int, device=integ.device)
    out = wp.zeros(n, dtype=wp.vec2, device=integ.device)
    kernel = integral_kernel(mutation)
    sums = []
    for f in range(frames):
        integ.render_frame(f)
        wp.launch(kernel, dim=n, inputs=[integ.dscene.scene, integ.params(f, 0), integ.gbuffers.previous,
                                         integ.reservoirs.previous, partner, types,
                                         int(diffuse_primaries), out], device=integ.device)
        sums.append(out.numpy().astype(np.float64).sum(axis=0))
    return np.array(sums)


def welch_z(s):
    d = s[:, 0] - s[:, 1]
    z = d.mean() / (d.std(ddof=1) / np.sqrt(len(d)))
    mdb = Z_CRIT * d.std(ddof=1) / np.sqrt(len(d)) / s[:, 1].mean()
    return z, mdb, s.mean(axis=0)


MDB_BOUND = 0.05
# The Cornell box with a light 3x larger (more paths reach it; diffuse: J has no heavy tail). On
# glossy primaries and glossy rc vertices p_hat_j(T x) J / p(x) is heavy-tailed (the source
# samples its own lobe, the destination's peak lies elsewhere) and sample means converge too
# slowly for this test at any affordable count: those shifts are covered by the D2/D3 tests.
SCENE = ("builtin:cornell-box", {"light_scale": 3.0})


def verdict(mutation, shift, frames):
    s = shift_integrals(SCENE[0], shift, mutation, frames=frames, max_depth=4, offset=2, **SCENE[1])
    z, mdb, m = welch_z(s)
    print(mutation, shift, "means", m, f"z {z:.2f} MDB {mdb:.4f}")
    return abs(z) < Z_CRIT and mdb < MDB_BOUND


@pytest.mark.parametrize("shift", ["hybrid", "reconnection", "replay"])
def test_shifts_preserve_integrals(shift):
    assert verdict("none", shift, 128)


# (mutation, shift, frames): caught means the verdict above fails. An inverted J makes the
# estimate's variance explode (MDB far above the bound); the others move the mean.
# Not caught here: drop_rc_pdf (the pdf ratio at z matters only on glossy z, where this test
# has no power; see the module docstring): not covered by this test.
MUTANTS = [("bsdf_twice", "reconnection", 64), ("invert_jacobian", "reconnection", 64),
           ("skip_destination_criteria", "hybrid", 256)]


@pytest.mark.parametrize("mutation,shift,frames", MUTANTS)
def test_shift_mutations_are_caught(mutation, shift, frames):
    assert not verdict(mutation, shift, frames)
