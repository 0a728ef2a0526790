"""Light sampling (NEE) against the light pdf: chi-square over directions, alpha = 1e-3 each.

The pdf of a direction is evaluated independently of the sampler: trace the direction from the
shading point and evaluate the density of whatever emitter it reaches (plus the environment's).
"""
import numpy as np
import pytest
import warp as wp

from restir.device.intersect import T_MAX, trace_closest
from restir.device.lights import env_dir_to_uv, env_pdf, env_uv_to_dir, sample_light, triangle_light_pdf
from restir.device.rng import rng_key, rng_uniform, rng_uniform2
from restir.device.scene_device import SceneDevice
from restir.image_io import write_exr
from tests.scenes import device_scene, sensor, triangle
from restir.validation.stats import chi2_test, expected_counts, histogram_directions, integration_points

ALPHA = 1e-3
N = 1_000_000
NT, NP, SUB = 40, 80, 32
X = wp.vec3(0.0, 0.0, 0.0)


@wp.kernel
def nee_kernel(scene: SceneDevice, x: wp.vec3, seed: wp.uint32, wi: wp.array(dtype=wp.vec3),
               pdf: wp.array(dtype=float), pdf_at_hit: wp.array(dtype=float), le: wp.array(dtype=wp.vec3)):
    i = wp.tid()
    key = rng_key(seed, wp.uint32(0), wp.uint32(0), wp.uint32(i))
    ls = sample_light(scene, x, rng_uniform(key, wp.uint32(0)), rng_uniform2(key, wp.uint32(1)))
    wi[i] = ls.wi
    pdf[i] = ls.pdf
    le[i] = ls.Le
    pdf_at_hit[i] = -1.0
    if ls.pdf > 0.0 and ls.is_env == 0:
        h = trace_closest(scene, x, ls.wi, T_MAX)
        if h.valid != 0:
            pdf_at_hit[i] = triangle_light_pdf(scene, h.tri, h.ng, ls.wi, h.t)


@wp.kernel
def direction_pdf_kernel(scene: SceneDevice, x: wp.vec3, dirs: wp.array(dtype=wp.vec3), out: wp.array(dtype=float)):
    i = wp.tid()
    d = dirs[i]
    p = env_pdf(scene, d)
    h = trace_closest(scene, x, d, T_MAX)
    if h.valid != 0:
        p += triangle_light_pdf(scene, h.tri, h.ng, d, h.t)
    out[i] = p


def emitters():
    # Three triangles around the origin, different powers; the last faces away from the origin.
    # None crosses the +-z poles, where (cos theta, phi) bins are too thin to integrate the pdf.
    return {
        "a": triangle([[1, -0.5, -0.5], [1, 0.5, -0.5], [1, 0, 0.6]], [4, 4, 4]),
        "b": triangle([[-0.5, 2, -0.4], [0.6, 2, 0], [-0.3, 2, 0.7]], [1, 2, 3]),
        "c": triangle([[0.6, 0.5, -1.5], [1.5, 1.2, -1.5], [1.3, 0.3, -1.5]], [10, 10, 10]),
    }


def check_sampler(ds):
    s = ds.scene
    arrs = [wp.zeros(N, dtype=t, device="cpu") for t in (wp.vec3, float, float, wp.vec3)]
    wp.launch(nee_kernel, dim=N, inputs=[s, X, wp.uint32(3), *arrs], device="cpu")
    wi, pdf, pdf_hit, le = [a.numpy() for a in arrs]
    ok = pdf > 0
    tri = ok & (pdf_hit >= 0)
    np.testing.assert_allclose(pdf[tri], pdf_hit[tri], rtol=2e-3)
    pts = integration_points(NT, NP, SUB).reshape(-1, 3).astype(np.float32)
    out = wp.zeros(len(pts), dtype=float, device="cpu")
    wp.launch(direction_pdf_kernel, dim=len(pts), inputs=[s, X, wp.array(pts, dtype=wp.vec3, device="cpu"), out], device="cpu")
    expected = expected_counts(out.numpy(), NT, NP, SUB, N)
    p, stat, dof = chi2_test(histogram_directions(wi[ok], NT, NP), expected)
    assert p > ALPHA, f"chi2={stat:.1f} dof={dof} p={p:.2e}"
    return wi, pdf, le


def test_area_lights():
    ds = device_scene({"type": "scene", "sensor": sensor(), **emitters()})
    wi, pdf, le = check_sampler(ds)
    # triangles are chosen in proportion to power (luminance x area)
    areas = ds.host.triangle_areas()
    power = ds.host.light_power()
    assert np.all(power > 0)
    # One-sided emitters: only "b" (above, normal -y) faces the origin. "a" and "c" face away:
    # they are still sampled with their pdf, but return no radiance.
    to_b = wi[:, 1] > 0.5
    assert to_b.any() and np.all(le[to_b] > 0) and np.all(le[~to_b] == 0)
    assert areas.min() > 0


def test_constant_environment_with_area_lights():
    ds = device_scene({"type": "scene", "sensor": sensor(), **emitters(),
                       "env": {"type": "constant", "radiance": {"type": "rgb", "value": [0.5, 0.5, 0.5]}}})
    check_sampler(ds)


@pytest.fixture()
def envmap_file(tmp_path):
    h, w = 32, 64
    y, x = np.mgrid[0:h, 0:w]
    img = np.full((h, w, 3), 0.05, np.float32)
    img += (np.exp(-((x - 40) ** 2 + (y - 10) ** 2) / 20.0) * 50)[..., None].astype(np.float32)
    img[:, :, 2] += (y / h).astype(np.float32)
    path = tmp_path / "env.exr"
    write_exr(str(path), img)
    return str(path)


def test_environment_map(envmap_file):
    from restir.scene.transforms import rotate

    ds = device_scene({"type": "scene", "sensor": sensor(), "floor": triangle([[5, -1, 5], [5, -1, -5], [-5, -1, 0]]),
                       "env": {"type": "envmap", "filename": envmap_file, "to_world": rotate([0, 1, 1], 30)}})
    check_sampler(ds)


@wp.kernel
def env_roundtrip_kernel(scene: SceneDevice, uv: wp.array(dtype=wp.vec2), out: wp.array(dtype=wp.vec2)):
    i = wp.tid()
    out[i] = env_dir_to_uv(scene, env_uv_to_dir(scene, uv[i]))


def test_environment_mapping_round_trip(envmap_file):
    ds = device_scene({"type": "scene", "sensor": sensor(), "floor": triangle([[5, -1, 5], [5, -1, -5], [-5, -1, 0]]),
                       "env": {"type": "envmap", "filename": envmap_file}})
    uv = np.random.default_rng(0).uniform(0.01, 0.99, (10000, 2)).astype(np.float32)
    out = wp.zeros(len(uv), dtype=wp.vec2, device="cpu")
    wp.launch(env_roundtrip_kernel, dim=len(uv), inputs=[ds.scene, wp.array(uv, dtype=wp.vec2, device="cpu"), out], device="cpu")
    np.testing.assert_allclose(out.numpy(), uv, atol=1e-4)
