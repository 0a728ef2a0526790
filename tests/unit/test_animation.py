"""Animated scenes (restir/scene/animation.py, scene/upload.py DeviceScene.set_frame): keyframe
interpolation as glTF defines it, the posed scene, the refusals, the device scene per frame with
the previous frame's kept, and the motion vectors of temporal reuse on a moving object."""
import numpy as np
import pytest
import warp as wp

import restir
from restir.device.camera import Camera, generate_ray
from restir.device.intersect import trace_closest
from restir.device.scene_device import SceneDevice
from restir.integrators.common.gbuffer import GBuffer
from restir.integrators.common.reuse_domains import NO_PIXEL, temporal_neighbor
from restir.integrators.common.shading import load_shading
from restir.scene.animation import Keyframes, Motion, animate, posed_scene, quaternion_matrix, slerp
from restir.scene.errors import SceneError
from restir.scene.upload import DeviceScene


def _quat(axis, deg):
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    h = np.radians(deg) / 2
    return np.array([*(a * np.sin(h)), np.cos(h)])


# ------------------------------------------------------------------ keyframes
def test_step_and_linear_keyframes_hold_outside_their_range():
    k = Keyframes([2, 4, 8], [[0.0], [10.0], [30.0]], "linear")
    assert k.at(0)[0] == 0.0 and k.at(2)[0] == 0.0 and k.at(3)[0] == 5.0 and k.at(6)[0] == 20.0
    assert k.at(8)[0] == 30.0 and k.at(100)[0] == 30.0
    s = Keyframes([2, 4, 8], [[0.0], [10.0], [30.0]], "step")
    assert s.at(3.99)[0] == 0.0 and s.at(4)[0] == 10.0 and s.at(7.9)[0] == 10.0 and s.at(8)[0] == 30.0


def test_cubic_spline_is_gltfs_hermite_form():
    """glTF 2.0 Appendix C at s = 1/2 over a key interval of dt = 2: p = v0/2 + dt b0/8 + v1/2
    - dt a1/8 (b0 the first key's out-tangent, a1 the second's in-tangent)."""
    v = np.array([[[9.0], [1.0], [3.0]],     # in, value, out of key 0
                  [[5.0], [4.0], [7.0]]])    # of key 1
    k = Keyframes([0, 2], v, "cubicspline")
    assert k.at(1.0)[0] == pytest.approx(1.0 / 2 + 2 * 3.0 / 8 + 4.0 / 2 - 2 * 5.0 / 8)
    assert k.at(0.0)[0] == 1.0 and k.at(2.0)[0] == 4.0


def test_rotations_interpolate_on_the_sphere():
    q0, q1 = _quat((0, 0, 1), 0), _quat((0, 0, 1), 90)
    k = Keyframes([0, 10], [q0, q1], "linear", quaternion=True)
    np.testing.assert_allclose(k.at(5), _quat((0, 0, 1), 45), atol=1e-12)
    # the shorter arc: -q1 is the same rotation
    np.testing.assert_allclose(slerp(q0, -q1, 0.5), _quat((0, 0, 1), 45), atol=1e-12)
    np.testing.assert_allclose(quaternion_matrix(_quat((0, 0, 1), 90)) @ [1, 0, 0], [0, 1, 0], atol=1e-12)


@pytest.mark.parametrize("args,match", [
    (([0, 1], [[0.0], [1.0]], "smooth"), "interpolation"),
    (([0, 0], [[0.0], [1.0]]), "increasing"),
    (([0, 1, 2], [[0.0], [1.0]]), "values of shape"),
    (([0, 1], [[0.0], [np.nan]]), "finite"),
    (([0, 1], [[0.0], [1.0]], "cubicspline"), "in-tangent"),
])
def test_bad_keyframes_are_refused(args, match):
    with pytest.raises(SceneError, match=match):
        Keyframes(*args)


def test_motion_rotates_and_scales_about_its_pivot():
    m = Motion(rotation=([0, 1], [_quat((0, 0, 1), 0), _quat((0, 0, 1), 90)]), scale=([0], [[2.0, 2.0, 2.0]]),
               translation=([0], [[0.0, 0.0, 5.0]]), pivot=[1.0, 1.0, 0.0])
    t = m.transform(1.0)
    np.testing.assert_allclose(t[:3, :3] @ [1, 1, 0] + t[:3, 3], [1, 1, 5], atol=1e-12)  # the pivot stays
    np.testing.assert_allclose(t[:3, :3] @ [2, 1, 0] + t[:3, 3], [1, 3, 5], atol=1e-12)  # 1 to the side: 2, turned


# ------------------------------------------------------------------ the posed scene and its refusals
def test_posed_scene_moves_objects_lights_and_emission():
    base = restir.load_scene("builtin:cornell-box", width=16, height=16)
    lo, hi = base.objects["short"]
    a = animate(base, {"short": Motion(rotation=([0, 4], [_quat((0, 1, 0), 0), _quat((0, 1, 0), 90)]),
                                       translation=([0, 4], [[0, 0, 0], [0.1, 0, 0]])),
                       "light": Motion(emission=([0, 2], [[1.0], [0.0]], "step"))})
    assert base.animation is None  # animate makes a copy
    p = posed_scene(a, 4)
    r = quaternion_matrix(_quat((0, 1, 0), 90))
    np.testing.assert_allclose(p.positions[lo:hi].reshape(-1, 3), base.positions[lo:hi].reshape(-1, 3) @ r.T + [0.1, 0, 0],
                               atol=1e-6)
    np.testing.assert_array_equal(p.positions[:lo], base.positions[:lo])
    l0, l1 = base.objects["light"]
    assert np.all(posed_scene(a, 1).tri_emission[l0:l1] == base.tri_emission[l0:l1])
    assert np.all(p.tri_emission[l0:l1] == 0.0) and p.light_power()[l0:l1].sum() == 0.0


def test_delta_lights_move_and_scale():
    base = restir.load_scene("builtin:many-delta-lights", width=16, height=16)
    d0 = base.delta_lights[0]
    a = animate(base, {"light0": Motion(translation=([0, 2], [[0, 0, 0], [0, -0.1, 0]]),
                                        emission=([0, 2], [[1.0], [3.0]]))})
    d = posed_scene(a, 1).delta_lights[0]
    np.testing.assert_allclose(d.position, np.asarray(d0.position) + [0, -0.05, 0], atol=1e-12)
    np.testing.assert_allclose(d.intensity, 2.0 * np.asarray(d0.intensity))
    assert base.delta_lights[0] is d0 and np.all(d0.intensity == base.delta_lights[0].intensity)


def test_animation_errors_are_refused_before_rendering():
    base = restir.load_scene("builtin:cornell-box", width=16, height=16)
    with pytest.raises(SceneError, match="'door'.*does not have"):
        animate(base, {"door": Motion()})
    with pytest.raises(SceneError, match="singular"):
        animate(base, {"short": Motion(scale=([0], [[1.0, 0.0, 1.0]]))})
    with pytest.raises(SceneError, match="mirrors"):
        animate(base, {"short": Motion(scale=([0], [[-1.0, 1.0, 1.0]]))})
    with pytest.raises(SceneError, match="not a dict"):
        animate(base, callback=lambda f: None)
    with pytest.raises(SceneError, match="4x4"):
        animate(base, callback=lambda f: {"short": {"to_world": np.eye(3)}})
    with pytest.raises(SceneError, match="emission factor"):
        animate(base, callback=lambda f: {"light": {"emission": -1.0}})


def test_a_callback_drives_the_scene():
    base = restir.load_scene("builtin:cornell-box", width=16, height=16)
    lo, hi = base.objects["tall"]
    a = animate(base, callback=lambda f: {"tall": {"to_world": np.array([[1, 0, 0, 0.01 * f], [0, 1, 0, 0],
                                                                         [0, 0, 1, 0], [0, 0, 0, 1.0]])}})
    p = posed_scene(a, 3)
    np.testing.assert_allclose(p.positions[lo:hi, :, 0], base.positions[lo:hi, :, 0] + 0.03, atol=1e-6)


# ------------------------------------------------------------------ the device scene per frame
@wp.kernel
def down_kernel(scene: SceneDevice, origins: wp.array(dtype=wp.vec3), out: wp.array(dtype=wp.int32)):
    i = wp.tid()
    out[i] = trace_closest(scene, origins[i], wp.vec3(0.0, -1.0, 0.0), 1.0e30).tri


def test_the_device_scene_follows_the_frames_and_keeps_the_previous_one(device):
    """A ray cast down onto where the short block will be misses it at frame 0 and hits it at
    frame 8; the struct of frame 0, kept by an integrator as its history's scene, still sees the
    block where it was once frame 8 is set. The light switched off leaves the light tables."""
    base = restir.load_scene("builtin:cornell-box", width=16, height=16)
    lo, hi = base.objects["short"]
    a = animate(base, {"short": Motion(translation=([0, 8], [[0, 0, 0], [0.3, 0, 0]])),
                       "light": Motion(emission=([0, 8], [[1.0], [0.0]], "step"))})
    centre = base.positions[lo:hi].reshape(-1, 3).mean(0)
    origins = wp.array(np.array([centre + [0.3, 0.4, 0], centre + [0, 0.4, 0]], np.float32), dtype=wp.vec3,
                       device=device)
    out = wp.zeros(2, dtype=wp.int32, device=device)
    d = DeviceScene(a, device)
    bytes0 = d.memory_bytes()
    first = d.scene
    wp.launch(down_kernel, dim=2, inputs=[first, origins, out], device=device)
    hits0 = out.numpy().copy()
    assert not lo <= hits0[0] < hi and lo <= hits0[1] < hi
    assert first.num_tri_lights == 2
    d.set_frame(8)
    wp.launch(down_kernel, dim=2, inputs=[d.scene, origins, out], device=device)
    hits8 = out.numpy().copy()
    assert lo <= hits8[0] < hi and not lo <= hits8[1] < hi
    assert d.scene.num_tri_lights == 0
    wp.launch(down_kernel, dim=2, inputs=[first, origins, out], device=device)
    np.testing.assert_array_equal(out.numpy(), hits0)
    assert d.memory_bytes() > bytes0  # both frames' geometry counted


# ------------------------------------------------------------------ motion vectors
@wp.kernel
def primary_kernel(scene: SceneDevice, cam: Camera, tri: wp.array(dtype=wp.int32), bary: wp.array(dtype=wp.vec2)):
    pixel = wp.tid()
    ray = generate_ray(cam, pixel % cam.width, pixel // cam.width, wp.vec2(0.5), wp.vec2(0.5))
    h = trace_closest(scene, ray.o, ray.d, 1.0e30)
    tri[pixel] = h.tri
    bary[pixel] = h.bary


@wp.kernel
def neighbor_kernel(scene: SceneDevice, prev_scene: SceneDevice, motion_scene: SceneDevice, cam: Camera,
                    gb: GBuffer, prev_gb: GBuffer, out: wp.array(dtype=wp.int32)):
    pixel = wp.tid()
    sc = load_shading(scene, gb, pixel)
    out[pixel] = NO_PIXEL
    if sc.valid != 0:
        out[pixel] = temporal_neighbor(prev_scene, motion_scene, cam, cam, prev_gb, sc, pixel).pixel


def _gbuffer(d, scene, n, device):
    gb = GBuffer()
    gb.tri = wp.zeros(n, dtype=wp.int32, device=device)
    gb.bary = wp.zeros(n, dtype=wp.vec2, device=device)
    gb.t = wp.zeros(1, dtype=float, device=device)
    gb.dir = wp.zeros(1, dtype=wp.vec3, device=device)
    gb.from_camera = 1
    gb.origin = wp.vec3(*d.host.camera.to_world[:3, 3].astype(np.float32))
    wp.launch(primary_kernel, dim=n, inputs=[scene, d.camera, gb.tri, gb.bary], device=device)
    return gb


def test_motion_vectors_follow_the_moving_object(device):
    """The short block slides 7 cm between two frames (4 px at 40x40). Its pixels' temporal
    technique, with the hit's own motion vector, is a pixel that saw the block the frame before
    (almost all of them); with the camera's motion alone (the still camera: the pixel itself) most
    of the pixels on its front and sides lose their history to the floor or the wall behind it."""
    base = restir.load_scene("builtin:cornell-box", width=40, height=40)
    lo, hi = base.objects["short"]
    a = animate(base, {"short": Motion(translation=([0, 1], [[0, 0, 0], [0.07, 0, 0]]))})
    n = 40 * 40
    d = DeviceScene(a, device)
    prev = d.scene
    prev_gb = _gbuffer(d, prev, n, device)
    d.set_frame(1)
    gb = _gbuffer(d, d.scene, n, device)
    tri_now, tri_then = gb.tri.numpy(), prev_gb.tri.numpy()
    on_block = (tri_now >= lo) & (tri_now < hi)
    out = wp.zeros(n, dtype=wp.int32, device=device)
    found = {}
    for name, motion in (("own", prev), ("camera", d.scene)):
        wp.launch(neighbor_kernel, dim=n, inputs=[d.scene, prev, motion, d.camera, gb, prev_gb, out], device=device)
        q = out.numpy()[on_block]
        ok = q != NO_PIXEL
        same = np.zeros(len(q), bool)
        same[ok] = (tri_then[q[ok]] >= lo) & (tri_then[q[ok]] < hi)
        found[name] = same.mean()
    print(f"{on_block.sum()} block pixels; history on the block: own motion {found['own']:.2f}, "
          f"camera's {found['camera']:.2f}")
    assert found["own"] > 0.85 and found["camera"] < found["own"] - 0.2


@wp.kernel
def rays_kernel(scene: SceneDevice, o: wp.array(dtype=wp.vec3), d: wp.array(dtype=wp.vec3),
                out: wp.array(dtype=wp.int32)):
    i = wp.tid()
    out[i] = trace_closest(scene, o[i], d[i], 1.0e30).tri


@pytest.mark.parametrize("tracer", ["auto", "warp"])
def test_frame_updates_equal_a_full_upload(device, tracer):
    """Frames after a slot's first write only what moves (the moving objects' triangles, the
    emitters' entries of the light tables) and refit (Embree's dynamic scene, or Warp's BVH): every
    array, the light tables and the hits of random rays equal those of the same frame uploaded
    whole."""
    from tests.scenes import motion_scene

    scene = motion_scene("all")
    rng = np.random.default_rng(3)
    n = 4096
    o = wp.array(rng.uniform([0.0, 0.0, -0.5], [0.55, 0.55, 0.0], (n, 3)).astype(np.float32), dtype=wp.vec3,
                 device=device)
    d = rng.normal(size=(n, 3))
    d[:, 2] = np.abs(d[:, 2])
    d = wp.array((d / np.linalg.norm(d, axis=1, keepdims=True)).astype(np.float32), dtype=wp.vec3, device=device)
    a_hits, b_hits = (wp.zeros(n, dtype=wp.int32, device=device) for _ in range(2))
    inc = DeviceScene(scene, device, tracer)
    for f in range(1, 8):
        inc.set_frame(f)
        whole = DeviceScene(scene, device, tracer)
        whole.set_frame(f)  # its other slot's first frame: everything uploaded
        a, b = inc.scene, whole.scene
        for name in ("positions", "normals", "tri_emission", "tri_light_pdf", "light_tri", "light_prob",
                     "light_alias", "delta_light_pmf"):
            np.testing.assert_array_equal(getattr(a, name).numpy(), getattr(b, name).numpy(), err_msg=f"{f} {name}")
        assert (a.num_tri_lights, a.env_select_prob) == (b.num_tri_lights, b.env_select_prob)
        wp.launch(rays_kernel, dim=n, inputs=[a, o, d, a_hits], device=device)
        wp.launch(rays_kernel, dim=n, inputs=[b, o, d, b_hits], device=device)
        np.testing.assert_array_equal(a_hits.numpy(), b_hits.numpy(), err_msg=f"frame {f}")
