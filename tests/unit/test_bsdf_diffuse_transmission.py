"""pbrt-v4's diffusetransmission BSDF (device/bsdfs/diffuse_transmission.py) against its
definition (R / pi on wi's side, T / pi on the other), reciprocity and energy. Its sampling
against its pdf (chi-square) and its lobes are in test_bsdf.py and test_bsdf_lobes.py."""
import numpy as np
import pytest
import warp as wp

from restir.device.bsdf import Material, bsdf_eval, bsdf_sample
from restir.device.rng import rng_key, rng_uniform, rng_uniform2
from restir.device.types import MAT_DIFFUSE_TRANSMISSION

from .test_bsdf import material

R, T = np.array([0.6, 0.3, 0.1]), np.array([0.2, 0.5, 0.3])


@wp.kernel
def eval_kernel(mat: Material, wi: wp.array(dtype=wp.vec3), wo: wp.array(dtype=wp.vec3), out: wp.array(dtype=wp.vec3)):
    i = wp.tid()
    out[i] = bsdf_eval(mat, wi[i], wo[i])


@wp.kernel
def albedo_kernel(mat: Material, wi: wp.vec3, out: wp.array(dtype=wp.vec3)):
    i = wp.tid()
    key = rng_key(wp.uint32(4), wp.uint32(0), wp.uint32(0), wp.uint32(i))
    s = bsdf_sample(mat, wi, rng_uniform(key, wp.uint32(0)), rng_uniform2(key, wp.uint32(1)))
    if s.valid != 0:
        out[i] = s.weight


def the_material():
    m = material(MAT_DIFFUSE_TRANSMISSION, twosided=1)
    m.reflectance = wp.vec3(*R)
    m.specular_transmittance = wp.vec3(*T)
    return m


def evaluate(mat, wi, wo):
    out = wp.zeros(len(wi), dtype=wp.vec3, device="cpu")
    wp.launch(eval_kernel, dim=len(wi), inputs=[mat, wp.array(wi, dtype=wp.vec3, device="cpu"),
                                                wp.array(wo, dtype=wp.vec3, device="cpu"), out], device="cpu")
    return out.numpy().astype(np.float64)


def sphere_dirs(rng, n):
    v = rng.normal(size=(n, 3))
    return (v / np.linalg.norm(v, axis=1, keepdims=True)).astype(np.float32)


def test_values_and_reciprocity():
    rng = np.random.default_rng(8)
    wi, wo = sphere_dirs(rng, 20000), sphere_dirs(rng, 20000)
    mat = the_material()
    f = evaluate(mat, wi, wo)
    same = (wi[:, 2] * wo[:, 2] > 0)[:, None]
    want = np.where(same, R, T) / np.pi * np.abs(wo[:, 2:3])
    np.testing.assert_allclose(f, want, rtol=1e-5, atol=1e-7)
    back = evaluate(mat, wo, wi) / np.abs(wi[:, 2:3])
    np.testing.assert_allclose(f / np.abs(wo[:, 2:3]), back, rtol=1e-5, atol=1e-7)


@pytest.mark.parametrize("theta,below", [(10.0, False), (70.0, False), (40.0, True)])
def test_albedo_is_r_plus_t(theta, below):
    """The sampler's albedo (mean weight, 200k samples) is R + T from either side."""
    t = np.radians(theta)
    wi = np.array([np.sin(t), 0.0, -np.cos(t) if below else np.cos(t)], np.float32)
    n = 200_000
    out = wp.zeros(n, dtype=wp.vec3, device="cpu")
    wp.launch(albedo_kernel, dim=n, inputs=[the_material(), wp.vec3(*wi), out], device="cpu")
    w = out.numpy().astype(np.float64)
    se = w.std(axis=0) / np.sqrt(n)
    assert np.all(np.abs(w.mean(axis=0) - (R + T)) < 4 * se + 1e-6), (w.mean(axis=0), R + T, se)
