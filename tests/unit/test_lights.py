"""Light sampling (NEE): which light, which point, and the returned density, each checked
against quantities computed independently on the host.

False-failure rates: the selection/position checks of one scene together have alpha = 1e-3
(Bonferroni-split over their comparisons), and the direction chi-square has alpha = 1e-3, so a
test function fails by chance at most 2e-3 of the time. The checks:

- selection: which emissive triangle the sampler returns, chi-square against the powers of the
  triangles computed on the host from the host Scene's vertices and emitted radiance; with an
  environment also present, the fraction of environment samples, binomial test against the
  documented environment-selection probability;
- position: the sampled points of each triangle, chi-square against uniform density by area
  over K^2 equal-area sub-triangles (barycentric cells);
- density: the returned solid-angle pdf equals P(select triangle) / area * dist^2 / |cos theta_l|
  (the area-to-solid-angle conversion of device/lights.py), recomputed on the host in float64,
  to float32 tolerance (not a statistical test);
- directions: chi-square over the sphere against the pdf of each direction, evaluated by another
  code path than the sampler's (trace the direction from the shading point and evaluate the
  density of whatever emitter it reaches, plus the environment's). That pdf reads the device's
  own light tables, so for area lights this is a sampler/pdf consistency check; the three
  checks above tie those tables to the scene. (For environment maps the tables are still only
  checked against themselves.)
"""
import numpy as np
import pytest
import warp as wp
from scipy import stats as sps

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
K = 8  # barycentric cells per triangle edge: K^2 equal-area sub-triangles
# Luminance of linear Rec. 709 / sRGB RGB: the weighting of "power" (luminance x area x pi for a
# one-sided diffuse emitter) that Scene.light_power and device/lights.py document.
LUMINANCE = np.array([0.2126, 0.7152, 0.0722])


@wp.kernel
def nee_kernel(scene: SceneDevice, x: wp.vec3, seed: wp.uint32, wi: wp.array(dtype=wp.vec3),
               pdf: wp.array(dtype=float), pdf_at_hit: wp.array(dtype=float), le: wp.array(dtype=wp.vec3),
               tri: wp.array(dtype=wp.int32), p: wp.array(dtype=wp.vec3), is_env: wp.array(dtype=wp.int32)):
    i = wp.tid()
    key = rng_key(seed, wp.uint32(0), wp.uint32(0), wp.uint32(i))
    ls = sample_light(scene, x, rng_uniform(key, wp.uint32(0)), rng_uniform2(key, wp.uint32(1)))
    wi[i] = ls.wi
    pdf[i] = ls.pdf
    le[i] = ls.Le
    tri[i] = ls.tri
    p[i] = ls.p
    is_env[i] = ls.is_env
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
    # "b" is not grey, so weighting by luminance and by, say, the RGB mean select differently.
    return {
        "a": triangle([[1, -0.5, -0.5], [1, 0.5, -0.5], [1, 0, 0.6]], [4, 4, 4]),
        "b": triangle([[-0.5, 2, -0.4], [0.6, 2, 0], [-0.3, 2, 0.7]], [1, 2, 3]),
        "c": triangle([[0.6, 0.5, -1.5], [1.5, 1.2, -1.5], [1.3, 0.3, -1.5]], [10, 10, 10]),
    }


def sample(ds, device):
    s = ds.scene
    arrs = [wp.zeros(N, dtype=t, device=device) for t in (wp.vec3, float, float, wp.vec3, wp.int32, wp.vec3, wp.int32)]
    wp.launch(nee_kernel, dim=N, inputs=[s, X, wp.uint32(3), *arrs], device=device)
    return dict(zip(("wi", "pdf", "pdf_hit", "le", "tri", "p", "is_env"), (a.numpy() for a in arrs)))


def check_directions(ds, device, smp):
    """Consistency of the sampler with the device's own pdf evaluation, in direction space."""
    s = ds.scene
    wi, pdf, pdf_hit = smp["wi"], smp["pdf"], smp["pdf_hit"]
    ok = pdf > 0
    tri = ok & (pdf_hit >= 0)
    np.testing.assert_allclose(pdf[tri], pdf_hit[tri], rtol=2e-3)
    pts = integration_points(NT, NP, SUB).reshape(-1, 3).astype(np.float32)
    out = wp.zeros(len(pts), dtype=float, device=device)
    wp.launch(direction_pdf_kernel, dim=len(pts), inputs=[s, X, wp.array(pts, dtype=wp.vec3, device=device), out],
              device=device)
    expected = expected_counts(out.numpy(), NT, NP, SUB, N)
    p, stat, dof = chi2_test(histogram_directions(wi[ok], NT, NP), expected)
    assert p > ALPHA, f"chi2={stat:.1f} dof={dof} p={p:.2e}"


def host_light_model(host):
    """Per-triangle selection probability among the triangle lights, area and unit normal, from
    the host Scene's vertices and emitted radiance only (float64)."""
    v = host.positions.astype(np.float64)
    cross = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
    area = 0.5 * np.linalg.norm(cross, axis=1)
    normal = cross / np.maximum(2 * area, 1e-300)[:, None]
    # Power of a one-sided diffuse emitter of radiance L: pi * area * L (luminance of it).
    power = np.pi * area * np.maximum(host.tri_emission.astype(np.float64) @ LUMINANCE, 0.0)
    return power / power.sum(), area, normal, v


def barycentric_cells(pts, v, k):
    """Cell index in [0, k^2) of each point of triangle v (3, 3): the triangle split into k^2
    congruent (equal-area) sub-triangles by lines of constant barycentric coordinate; -1 outside."""
    e1, e2 = v[1] - v[0], v[2] - v[0]
    (b1, b2), *_ = np.linalg.lstsq(np.stack([e1, e2], 1), (pts - v[0]).T, rcond=None)
    resid = np.linalg.norm(pts - (v[0] + np.outer(b1, e1) + np.outer(b2, e2)), axis=1)
    assert resid.max() < 1e-5 * max(1.0, np.abs(v).max()), "sampled point off the triangle's plane"
    eps = 1e-6  # float32 rounding of points on the edges
    inside = (b1 >= -eps) & (b2 >= -eps) & (b1 + b2 <= 1 + eps)
    b1, b2 = np.clip(b1, 0, 1), np.clip(b2, 0, 1)
    s = np.maximum(b1 + b2, 1.0) * (1 + 1e-9)  # rounding past the far edge: pull back inside
    b1, b2 = b1 / s, b2 / s
    i = np.minimum((k * b1).astype(int), k - 1)
    j = np.minimum((k * b2).astype(int), k - 1)
    upper = (k * b1 - i) + (k * b2 - j) >= 1
    # row i holds the lower cells j = 0..k-1-i, then (after all lower cells) the upper cells j = 0..k-2-i
    lower_id = i * k - i * (i - 1) // 2 + j
    upper_id = k * (k + 1) // 2 + i * (k - 1) - i * (i - 1) // 2 + j
    cell = np.where(upper, upper_id, lower_id)
    cell[~inside | (i + j > np.where(upper, k - 2, k - 1))] = -1
    return cell


def check_light_selection(ds, smp, p_env):
    """Selection frequencies, uniform-by-area points and the returned pdf (see module docstring).

    p_env: the probability that NEE picks the environment (0 without one)."""
    host = ds.host
    p_sel, area, normal, v = host_light_model(host)
    emissive = np.nonzero(p_sel > 0)[0]
    tri, is_env, pts, pdf = smp["tri"], smp["is_env"], smp["p"].astype(np.float64), smp["pdf"].astype(np.float64)
    on_tri = is_env == 0
    alpha = ALPHA / (2 + len(emissive))  # environment fraction, selection, one position test per triangle

    # environment vs triangles: binomial test of the number of environment samples
    n_env = int((~on_tri).sum())
    if p_env in (0.0, 1.0):
        assert n_env == N * p_env
    else:
        p = sps.binomtest(n_env, N, p_env).pvalue
        assert p > alpha, f"{n_env} environment samples of {N}, expected {p_env * N:.0f} (p={p:.2e})"

    # which triangle: chi-square against the host powers; a non-emissive triangle never
    t = tri[on_tri]
    assert np.all((t >= 0) & (t < host.num_triangles)), "sampled triangle index out of range"
    counts = np.bincount(t, minlength=host.num_triangles)
    assert counts[p_sel == 0].sum() == 0, "a non-emissive triangle was selected"
    p, stat, dof = chi2_test(counts[emissive], p_sel[emissive] * len(t), min_expected=0)
    assert p > alpha, f"selection: counts {counts[emissive]}, expected {p_sel[emissive] * len(t)}, chi2={stat:.1f} p={p:.2e}"

    # where on the triangle: uniform by area
    for k_tri in emissive:
        sel = on_tri & (tri == k_tri)
        cell = barycentric_cells(pts[sel], v[k_tri], K)
        assert np.all(cell >= 0), f"triangle {k_tri}: {np.sum(cell < 0)} points outside the triangle"
        h = np.bincount(cell, minlength=K * K)
        p, stat, dof = chi2_test(h, np.full(K * K, sel.sum() / (K * K)), min_expected=0)
        assert p > alpha, f"triangle {k_tri}: points not uniform by area, chi2={stat:.1f} dof={dof} p={p:.2e}"

    # the returned density: P(triangle) / area, converted to solid angle at X
    x = np.array([X[0], X[1], X[2]], np.float64)
    d = pts[on_tri] - x
    dist = np.linalg.norm(d, axis=1)
    cos_l = np.abs(np.einsum("ij,ij->i", normal[tri[on_tri]], d / dist[:, None]))
    want = (1.0 - p_env) * p_sel[tri[on_tri]] / area[tri[on_tri]] * dist ** 2 / cos_l
    np.testing.assert_allclose(pdf[on_tri], want, rtol=2e-5)


def test_area_lights(device):
    ds = device_scene({"type": "scene", "sensor": sensor(), **emitters()}, device)
    smp = sample(ds, device)
    check_light_selection(ds, smp, p_env=0.0)
    check_directions(ds, device, smp)
    # One-sided emitters: only "b" (above, normal -y) faces the origin. "a" and "c" face away:
    # they are still sampled with their pdf, but return no radiance.
    wi, le = smp["wi"], smp["le"]
    to_b = wi[:, 1] > 0.5
    assert to_b.any() and np.all(le[to_b] > 0) and np.all(le[~to_b] == 0)


def test_constant_environment_with_area_lights(device):
    ds = device_scene({"type": "scene", "sensor": sensor(), **emitters(),
                       "env": {"type": "constant", "radiance": {"type": "rgb", "value": [0.5, 0.5, 0.5]}}}, device)
    smp = sample(ds, device)
    # The environment-vs-triangles split is a documented parameter of the device scene
    # (SceneDevice.env_select_prob: "P(NEE picks the environment)"), not a table.
    p_env = float(ds.scene.env_select_prob)
    assert 0.0 < p_env < 1.0
    check_light_selection(ds, smp, p_env)
    check_directions(ds, device, smp)


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


def test_environment_map(envmap_file, device):
    from restir.scene.transforms import rotate

    ds = device_scene({"type": "scene", "sensor": sensor(), "floor": triangle([[5, -1, 5], [5, -1, -5], [-5, -1, 0]]),
                       "env": {"type": "envmap", "filename": envmap_file, "to_world": rotate([0, 1, 1], 30)}}, device)
    check_directions(ds, device, sample(ds, device))


@wp.kernel
def env_roundtrip_kernel(scene: SceneDevice, uv: wp.array(dtype=wp.vec2), out: wp.array(dtype=wp.vec2)):
    i = wp.tid()
    out[i] = env_dir_to_uv(scene, env_uv_to_dir(scene, uv[i]))


def test_environment_mapping_round_trip(envmap_file, device):
    ds = device_scene({"type": "scene", "sensor": sensor(), "floor": triangle([[5, -1, 5], [5, -1, -5], [-5, -1, 0]]),
                       "env": {"type": "envmap", "filename": envmap_file}}, device)
    uv = np.random.default_rng(0).uniform(0.01, 0.99, (10000, 2)).astype(np.float32)
    out = wp.zeros(len(uv), dtype=wp.vec2, device=device)
    wp.launch(env_roundtrip_kernel, dim=len(uv), inputs=[ds.scene, wp.array(uv, dtype=wp.vec2, device=device), out],
              device=device)
    np.testing.assert_allclose(out.numpy(), uv, atol=1e-4)
