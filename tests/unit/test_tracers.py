"""Embree (CPU) and Warp's BVH return the same closest hits and visibility on the same rays.

Embree traces on the CPU only, so its side always runs there; Warp's side runs on the device
under test (`pytest --device cuda`: Warp's CUDA BVH against Embree).
"""
import numpy as np
import pytest
import warp as wp

import restir
from restir.device.intersect import is_visible, trace_closest
from restir.device.scene_device import SceneDevice
from restir.embree import library
from restir.scene.upload import DeviceScene
from tests.shared_scenes import scene_path



@wp.kernel
def rays_kernel(scene: SceneDevice, o: wp.array(dtype=wp.vec3), d: wp.array(dtype=wp.vec3),
                t: wp.array(dtype=float), tri: wp.array(dtype=wp.int32), p: wp.array(dtype=wp.vec3),
                vis: wp.array(dtype=wp.int32)):
    i = wp.tid()
    h = trace_closest(scene, o[i], d[i], 1.0e30)
    t[i] = wp.where(h.valid != 0, h.t, -1.0)
    tri[i] = h.tri
    p[i] = h.p
    vis[i] = wp.where(is_visible(scene, o[i], d[i], 2.0), 1, 0)


def trace(ds, o, d, device):
    n = len(o)
    outs = [wp.zeros(n, dtype=ty, device=device) for ty in (float, wp.int32, wp.vec3, wp.int32)]
    wp.launch(rays_kernel, dim=n, inputs=[ds.scene, wp.array(o, dtype=wp.vec3, device=device),
                                          wp.array(d, dtype=wp.vec3, device=device), *outs], device=device)
    return [x.numpy() for x in outs]


def camera_like_rays(scene, n, rng):
    """Rays from inside the scene's bounds, in random directions (origins not on surfaces)."""
    lo, hi = scene.bounds()
    o = lo + (hi - lo) * rng.uniform(0.05, 0.95, (n, 3))
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    return o.astype(np.float32), d.astype(np.float32)


@pytest.mark.skipif(library() is None, reason="embreex not installed")
@pytest.mark.parametrize("spec", ["builtin:cornell-box", "builtin:cornell-box-glossy", "veach-bidir", "veach-mis"])
def test_embree_and_warp_agree(spec, device):
    wp.init()
    if not spec.startswith("builtin:"):
        spec = str(scene_path(spec))
    scene = restir.load_scene(spec)
    rng = np.random.default_rng(0)
    o, d = camera_like_rays(scene, 200_000, rng)
    # Embree is a CPU library (DeviceScene refuses it elsewhere): its side stays on the CPU.
    a = trace(DeviceScene(scene, "cpu", "embree"), o, d, "cpu")
    b = trace(DeviceScene(scene, device, "warp"), o, d, device)
    hit_a, hit_b = a[0] >= 0, b[0] >= 0
    both = hit_a & hit_b
    # Rays may disagree only where they graze an edge or start inside thin geometry.
    assert np.mean(hit_a != hit_b) < 1e-4
    same_t = np.abs(a[0][both] - b[0][both]) <= 1e-4 * np.maximum(1.0, b[0][both])
    assert np.mean(~same_t) < 1e-3
    close = both & (np.abs(a[0] - b[0]) <= 1e-4 * np.maximum(1.0, b[0]))
    np.testing.assert_allclose(a[2][close], b[2][close], atol=1e-3 * max(1.0, float(np.abs(scene.bounds()).max())))
    assert np.mean(a[3] != b[3]) < 1e-4
