"""The shared reuse domains (restir/integrators/common/reuse_domains.py): temporal reprojection,
spatial neighbour selection and the default radius rule."""
import numpy as np
import pytest
import warp as wp

import restir
from restir.config import ConfigError
from restir.device.camera import Camera, generate_ray
from restir.integrators.common.reuse_domains import (NO_PIXEL, reciprocal_pairing,
                                                     reciprocal_partner, reproject, resolve_spatial_radius,
                                                     spatial_neighbor, spatial_radius_for)
from restir.scene.transforms import rotate
from restir.scene.upload import DeviceScene


@wp.kernel
def reproject_kernel(cam: Camera, prev: Camera, depth: float, u: wp.vec2, out: wp.array(dtype=wp.int32)):
    pixel = wp.tid()
    # a point seen through the pixel at the filter offset drawn from u
    ray = generate_ray(cam, pixel % cam.width, pixel // cam.width, u, wp.vec2(0.5))
    out[pixel] = reproject(cam, prev, pixel, ray.o + ray.d * depth, ray.o + ray.d * depth)


def test_reprojection_under_a_still_camera_is_the_pixel_itself(device):
    """Whatever the primary ray's filter offset, also one that reaches into a neighbouring pixel
    (the tent filter's offsets reach +-1 px): a pixel's history is its own."""
    scene = restir.load_scene("builtin:cornell-box", width=40, height=30)
    cam = DeviceScene(scene, device).camera
    out = wp.zeros(40 * 30, dtype=wp.int32, device=device)
    for u in ((0.3, 0.7), (0.02, 0.97), (0.99, 0.01)):
        wp.launch(reproject_kernel, dim=40 * 30, inputs=[cam, cam, 500.0, wp.vec2(*u), out], device=device)
        np.testing.assert_array_equal(out.numpy(), np.arange(40 * 30))


def test_reprojection_follows_the_motion_of_the_hit(device):
    """The camera turned by about 3 pixels: each pixel's history is the pixel that its primary
    hit's motion leads to (the same offset for every pixel of a distant point, up to 1 px of
    perspective), off-screen ones NO_PIXEL; a point behind the previous camera has none."""
    scene = restir.load_scene("builtin:cornell-box", width=40, height=30)
    moved = restir.load_scene("builtin:cornell-box", width=40, height=30)
    fov = 2.0 * np.degrees(np.arctan(scene.camera.tan_half()[1]))
    moved.camera.to_world = scene.camera.to_world @ rotate((0, 1, 0), 3.0 * fov / 30.0)
    cam, prev = DeviceScene(scene, device).camera, DeviceScene(moved, device).camera
    out = wp.zeros(40 * 30, dtype=wp.int32, device=device)
    wp.launch(reproject_kernel, dim=40 * 30, inputs=[cam, prev, 500.0, wp.vec2(0.02, 0.97), out], device=device)
    got = out.numpy().reshape(30, 40)
    on = got != NO_PIXEL
    dx = (got % 40 - np.arange(40)[None, :])[on]
    dy = (got // 40 - np.arange(30)[:, None])[on]
    assert on.sum() > 30 * 30 and set(np.unique(dy)) <= {-1, 0, 1}
    assert 2 <= abs(np.median(dx)) <= 4 and np.ptp(dx) <= 2
    assert np.all(~on[:, :2]) or np.all(~on[:, -2:])  # the columns that left the screen
    wp.launch(reproject_kernel, dim=40 * 30, inputs=[cam, prev, -500.0, wp.vec2(0.3, 0.7), out], device=device)
    assert np.all(out.numpy() == NO_PIXEL)  # behind the camera


@wp.kernel
def neighbor_kernel(u: wp.array(dtype=wp.vec2), pixel: int, width: int, height: int, radius: float,
                    out: wp.array(dtype=wp.int32)):
    i = wp.tid()
    out[i] = spatial_neighbor(u[i], pixel, width, height, radius)


@pytest.mark.parametrize("radius", [2.0, 7.5])
def test_spatial_neighbors_are_uniform_in_the_disk(radius, device):
    """Neighbours lie within radius + 0.5 px (rounding) and never on the pixel itself; each
    offset is chosen in proportion to the disk area that rounds to it (chi-square, alpha 1e-3)."""
    from restir.validation.stats import chi2_test

    rng = np.random.default_rng(1)
    n = 400_000
    u = rng.random((n, 2)).astype(np.float32)
    w, h, px, py = 64, 48, 30, 20
    out = wp.zeros(n, dtype=wp.int32, device=device)
    wp.launch(neighbor_kernel, dim=n, inputs=[wp.array(u, dtype=wp.vec2, device=device), py * w + px, w, h, radius, out],
              device=device)
    q = out.numpy()
    valid = q != NO_PIXEL
    dx, dy = q[valid] % w - px, q[valid] // w - py
    assert np.all(dx * dx + dy * dy <= (radius + 0.71) ** 2) and not np.any((dx == 0) & (dy == 0))
    # expected: area of the disk rounding to each offset, by a fine grid over the disk
    g = (np.arange(2000) + 0.5) / 2000 * 2 - 1
    X, Y = np.meshgrid(g, g)
    inside = X * X + Y * Y <= 1
    ox, oy = np.round(X[inside] * radius).astype(int), np.round(Y[inside] * radius).astype(int)
    keys, area = np.unique(ox * 1000 + oy, return_counts=True)
    keep = keys != 0
    expected = area[keep] / area.sum() * n
    got = dict(zip(*np.unique(dx * 1000 + dy, return_counts=True)))
    counts = np.array([got.get(k, 0) for k in keys[keep]])
    assert counts.sum() == valid.sum()
    p, stat, dof = chi2_test(counts, expected, min_expected=5)
    assert p > 1e-3, (stat, dof)
    # off screen: a corner pixel loses about three quarters of its disk
    wp.launch(neighbor_kernel, dim=n, inputs=[wp.array(u, dtype=wp.vec2, device=device), 0, w, h, radius, out],
              device=device)
    assert 0.6 < np.mean(out.numpy() == NO_PIXEL) < 0.9


@wp.kernel
def partner_kernel(u: wp.array(dtype=wp.vec4), width: int, height: int, radius: float,
                   out: wp.array2d(dtype=wp.int32)):
    d, pixel = wp.tid()
    v = u[d]
    out[d, pixel] = reciprocal_partner(pixel, width, height,
                                       reciprocal_pairing(radius, wp.vec2(v[0], v[1]), wp.vec2(v[2], v[3])))


@pytest.mark.parametrize("radius", [2.0, 2.37, 9.5])
def test_reciprocal_pairings_are_matchings_within_the_radius(radius, device):
    """spatial.reciprocal's pairings: for every draw, partner(partner(p)) = p (the neighbour's
    neighbour is the pixel: what lets one pair of shifts serve both), never the pixel itself,
    within the radius (+0.71 px of rounding), off screen only near the border; and within one
    draw the offsets differ from pixel to pixel, and over draws they cover the disk's offsets
    (the mean distance is within 30% of the disk's own rounded neighbours')."""
    rng = np.random.default_rng(2)
    draws, w, h = 400, 37, 29
    u = wp.array(rng.random((draws, 4)).astype(np.float32), dtype=wp.vec4, device=device)
    out = wp.zeros((draws, w * h), dtype=wp.int32, device=device)
    wp.launch(partner_kernel, dim=(draws, w * h), inputs=[u, w, h, radius, out], device=device)
    q = out.numpy()
    p = np.broadcast_to(np.arange(w * h), q.shape)
    valid = q != NO_PIXEL
    assert valid.mean() > 0.7
    assert np.all(q[valid] != p[valid])
    back = np.take_along_axis(q, np.where(valid, q, 0), axis=1)
    assert np.all(back[valid] == p[valid])  # an involution
    dx, dy = q % w - p % w, q // w - p // w
    dist = np.hypot(dx, dy)[valid]
    assert dist.max() <= radius + 0.71
    offsets = {(a, b) for a, b in zip(dx[valid], dy[valid])}
    disk = {(a, b) for a in range(-10, 11) for b in range(-10, 11) if 0 < a * a + b * b <= radius * radius}
    assert len(offsets & disk) >= 0.8 * len(disk)
    per_draw = [len(set(zip(dx[d][valid[d]], dy[d][valid[d]]))) for d in range(draws)]
    assert min(per_draw) >= 2  # not one offset for the whole screen
    mean_disk = np.mean([np.hypot(a, b) for a, b in disk])
    assert abs(dist.mean() / mean_disk - 1) < 0.3, (dist.mean(), mean_disk)


def test_spatial_radius_rule():
    """The 1080-line radius in pixels at and below 1080 lines (not scaled down), scaled up above."""
    assert spatial_radius_for(15.0, 1080) == 15.0
    assert spatial_radius_for(15.0, 2160) == 30.0
    assert spatial_radius_for(15.0, 128) == 15.0
    assert spatial_radius_for(15.0, 256) == 15.0
    assert resolve_spatial_radius("auto", 15.0, 512) == 15.0
    assert resolve_spatial_radius("4.5", 15.0, 512) == 4.5 and resolve_spatial_radius(6, 15.0, 512) == 6.0
    for bad in ("-1", "0", "wide", None):
        with pytest.raises(ConfigError):
            resolve_spatial_radius(bad, 15.0, 512)


def test_default_radius_is_reported_in_pixels():
    scene = restir.load_scene("builtin:cornell-box", width=24, height=256)
    r = restir.render(scene, restir.RenderConfig(method="restir-di", spp=1, frames=1))
    assert r.stats["settings"]["spatial.radius"] == 5.0  # ReSTIR DI's 1080-line radius, not scaled down
    with pytest.raises(ConfigError):
        restir.render(scene, restir.RenderConfig(method="restir-di", spp=1, settings={"spatial.radius": "-3"}))
