"""Delta lights and the thin lens: the loader's reading of Mitsuba 3's point, spot and directional
emitters and thinlens sensor (values, defaults, refusals), the spot falloffs of device/delta_lights.py
at points where each format's definition gives a known value, what a delta light sends toward a
point, and light selection by power across emissive triangles and delta lights (sample_light,
chi-square against the powers computed on the host; alpha = 1e-3, the test's false-failure rate).
"""
import math

import numpy as np
import pytest
import warp as wp

import restir
from restir.device.delta_lights import DeltaLight, delta_arrival, spot_falloff
from restir.device.lights import sample_light
from restir.device.rng import rng_key, rng_uniform, rng_uniform2
from restir.device.scene_device import SceneDevice
from restir.device.types import (DELTA_DIRECTIONAL, DELTA_POINT, DELTA_SPOT, FALLOFF_LINEAR_ANGLE, FALLOFF_SMOOTHSTEP,
                                 FALLOFF_SQUARED_RAMP, LIGHT_DELTA_BASE)
from restir.scene.errors import SceneError
from restir.scene.upload import DeviceScene
from restir.validation.stats import chi2_test

LUMINANCE = np.array([0.2126, 0.7152, 0.0722])
ROOM = """<scene version="3.0.0">
    <sensor type="{sensor}">{lens}<float name="fov" value="45"/>
        <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film></sensor>
    <shape type="rectangle"><transform name="to_world"><scale value="2"/></transform></shape>
    <shape type="rectangle"><transform name="to_world"><scale value="0.5"/><translate z="3"/></transform>
        <emitter type="area"><rgb name="radiance" value="2, 2, 2"/></emitter></shape>
    {emitters}
</scene>
"""


def load(tmp_path, emitters: str = "", sensor: str = "perspective", lens: str = ""):
    path = tmp_path / "scene.xml"
    path.write_text(ROOM.format(emitters=emitters, sensor=sensor, lens=lens))
    return restir.load_scene(str(path))


def test_point_spot_and_directional_are_read_as_mitsuba_defines_them(tmp_path):
    s = load(tmp_path, """
    <emitter type="point"><point name="position" value="1, 2, 3"/><rgb name="intensity" value="4, 5, 6"/></emitter>
    <emitter type="point"><transform name="to_world"><translate x="-1"/></transform></emitter>
    <emitter type="spot"><transform name="to_world"><lookat origin="0, 1, 0" target="0, 1, 5" up="0, 1, 0"/></transform>
        <rgb name="intensity" value="2"/><float name="cutoff_angle" value="30"/></emitter>
    <emitter type="directional"><vector name="direction" value="0, 0, -2"/><rgb name="irradiance" value="3"/></emitter>
    """)
    p1, p2, spot, sun = s.delta_lights
    assert p1.kind == "point" and np.allclose(p1.position, [1, 2, 3]) and np.allclose(p1.intensity, [4, 5, 6])
    assert np.allclose(p2.position, [-1, 0, 0]) and np.allclose(p2.intensity, 1.0)  # Mitsuba's default intensity 1
    assert spot.kind == "spot" and np.allclose(spot.position, [0, 1, 0]) and np.allclose(spot.axis, [0, 0, 1])
    assert spot.outer == pytest.approx(math.radians(30)) and spot.inner == pytest.approx(math.radians(22.5))
    assert spot.falloff == "linear_angle"
    assert sun.kind == "directional" and np.allclose(sun.axis, [0, 0, -1]) and np.allclose(sun.intensity, 3.0)


@pytest.mark.parametrize("emitters, message", [
    ('<emitter type="spot"><float name="cutoff_angle" value="10"/><float name="beam_width" value="20"/></emitter>',
     "beam_width"),
    ('<emitter type="spot"><float name="cutoff_angle" value="0"/></emitter>', "cutoff_angle"),
    ('<emitter type="point"><point name="position" value="0, 0, 1"/>'
     '<transform name="to_world"><translate x="1"/></transform></emitter>', "not both"),
    ('<emitter type="directional"><vector name="direction" value="0, 0, 0"/></emitter>', "direction is zero"),
    ('<emitter type="point"><rgb name="intensity" value="-1"/></emitter>', "non-negative"),
    ('<emitter type="spot"><texture name="texture" type="checkerboard"/></emitter>', "texture"),
    ('<emitter type="spot"><point name="position" value="0, 1, 0"/></emitter>', "placed and aimed by 'to_world'"),
    ('<emitter type="spot"><vector name="direction" value="0, -1, 0"/></emitter>', "placed and aimed by 'to_world'"),
])
def test_bad_delta_lights_are_refused(tmp_path, emitters, message):
    with pytest.raises(SceneError, match=message):
        load(tmp_path, emitters)


def test_thinlens_is_read_and_checked(tmp_path):
    s = load(tmp_path, sensor="thinlens", lens='<float name="aperture_radius" value="0.1"/>')
    assert s.camera.aperture_radius == 0.1 and s.camera.focus_distance == 1.0e4  # Mitsuba: far_clip
    s = load(tmp_path, sensor="thinlens",
             lens='<float name="aperture_radius" value="0.2"/><float name="focus_distance" value="3"/>')
    assert s.camera.focus_distance == 3.0
    with pytest.raises(SceneError, match="aperture_radius"):
        load(tmp_path, sensor="thinlens")  # Mitsuba 3 requires it
    with pytest.raises(SceneError, match="aperture_radius needs a thinlens sensor"):
        load(tmp_path, lens='<float name="aperture_radius" value="0.2"/>')  # on a perspective sensor
    with pytest.raises(SceneError, match="focus_distance"):
        load(tmp_path, sensor="thinlens",
             lens='<float name="aperture_radius" value="0.2"/><float name="focus_distance" value="-1"/>')


@wp.kernel
def falloff_kernel(lights: wp.array(dtype=DeltaLight), cosines: wp.array(dtype=float), out: wp.array(dtype=float)):
    i, j = wp.tid()
    out[i * cosines.shape[0] + j] = spot_falloff(lights[i], cosines[j])


def spot(falloff: int, inner_deg: float, outer_deg: float) -> DeltaLight:
    s = DeltaLight()
    s.kind = DELTA_SPOT
    s.falloff = falloff
    s.inner, s.outer = math.radians(inner_deg), math.radians(outer_deg)
    s.cos_inner, s.cos_outer = math.cos(s.inner), math.cos(s.outer)
    return s


def test_spot_falloffs_follow_each_formats_definition():
    """At the inner cone 1, outside the outer cone 0, and halfway between the cones: Mitsuba 3's
    (linear in the angle) 1/2 at the middle angle; pbrt-v4's smoothstep 1/2 at the middle cosine;
    glTF's squared ramp 1/4 at the middle cosine."""
    wp.init()
    lights = [spot(FALLOFF_LINEAR_ANGLE, 10, 30), spot(FALLOFF_SMOOTHSTEP, 10, 30), spot(FALLOFF_SQUARED_RAMP, 10, 30)]
    mid_cos = 0.5 * (math.cos(math.radians(10)) + math.cos(math.radians(30)))
    cosines = [1.0, math.cos(math.radians(10)), math.cos(math.radians(20)), mid_cos, math.cos(math.radians(30.01)),
               -1.0]
    out = wp.zeros(len(lights) * len(cosines), dtype=float)
    wp.launch(falloff_kernel, dim=(len(lights), len(cosines)),
              inputs=[wp.array(lights, dtype=DeltaLight), wp.array(cosines, dtype=float)], outputs=[out])
    f = out.numpy().reshape(len(lights), len(cosines))
    assert np.allclose(f[:, :2], 1.0, atol=1e-5) and np.allclose(f[:, 4:], 0.0)
    assert f[0, 2] == pytest.approx(0.5, abs=1e-4)  # Mitsuba: the middle angle
    assert f[1, 3] == pytest.approx(0.5, abs=1e-4)  # pbrt-v4: the middle cosine
    assert f[2, 3] == pytest.approx(0.25, abs=1e-4)  # glTF: the middle cosine, squared
    assert 0.0 < f[0, 3] < 1.0 and f[1, 2] != pytest.approx(0.5, abs=1e-3)  # the two middles differ


@wp.kernel
def arrival_kernel(lights: wp.array(dtype=DeltaLight), x: wp.vec3, out: wp.array(dtype=wp.vec4)):
    i = wp.tid()
    a = delta_arrival(lights[i], x)
    out[2 * i] = wp.vec4(a.wi[0], a.wi[1], a.wi[2], a.dist)
    out[2 * i + 1] = wp.vec4(a.Le[0], a.Le[1], a.Le[2], 0.0)


def test_what_a_delta_light_sends_toward_a_point():
    """A point: I / d^2 from its direction; a spot on its axis: I / d^2, off its outer cone: 0; a
    directional light: E from against its direction, at any distance."""
    wp.init()
    point = DeltaLight()
    point.kind, point.p, point.I = DELTA_POINT, wp.vec3(0.0, 2.0, 0.0), wp.vec3(4.0, 8.0, 12.0)
    on_axis = spot(FALLOFF_LINEAR_ANGLE, 10, 20)
    on_axis.p, on_axis.axis, on_axis.I = wp.vec3(0.0, 0.0, 4.0), wp.vec3(0.0, 0.0, -1.0), wp.vec3(16.0)
    off_axis = spot(FALLOFF_LINEAR_ANGLE, 10, 20)
    off_axis.p, off_axis.axis, off_axis.I = wp.vec3(0.0, 0.0, 4.0), wp.vec3(1.0, 0.0, 0.0), wp.vec3(16.0)
    sun = DeltaLight()
    sun.kind, sun.axis, sun.I = DELTA_DIRECTIONAL, wp.vec3(0.0, -1.0, 0.0), wp.vec3(3.0)
    out = wp.zeros(8, dtype=wp.vec4)
    wp.launch(arrival_kernel, dim=4, inputs=[wp.array([point, on_axis, off_axis, sun], dtype=DeltaLight),
                                             wp.vec3(0.0)], outputs=[out])
    o = out.numpy()
    assert np.allclose(o[0], [0, 1, 0, 2]) and np.allclose(o[1][:3], [1, 2, 3])
    assert np.allclose(o[2], [0, 0, 1, 4]) and np.allclose(o[3][:3], 1.0)
    assert np.allclose(o[5][:3], 0.0)
    assert np.allclose(o[6][:3], [0, 1, 0]) and o[6][3] > 1e20 and np.allclose(o[7][:3], 3.0)


@wp.kernel
def selection_kernel(scene: SceneDevice, seed: wp.uint32, light: wp.array(dtype=wp.int32),
                     pdf: wp.array(dtype=float), is_delta: wp.array(dtype=wp.int32)):
    i = wp.tid()
    key = rng_key(seed, wp.uint32(0), wp.uint32(0), wp.uint32(i))
    ls = sample_light(scene, wp.vec3(0.0, 0.0, 0.5), rng_uniform(key, wp.uint32(0)), rng_uniform2(key, wp.uint32(1)))
    light[i] = ls.tri
    pdf[i] = ls.pdf
    is_delta[i] = ls.is_delta


@pytest.mark.parametrize("env", [False, True])
def test_lights_are_selected_in_proportion_to_power(tmp_path, env):
    """Which light sample_light picks, against the powers computed here from the scene's
    description: an area light's pi L A, a point's 4 pi I, a spot's I times its falloff over the
    sphere (the Mitsuba falloff integrated in closed form), a directional light's E pi r^2 (r:
    the radius of the bounding box's sphere); with a constant environment, half the samples."""
    emitters = """
    <emitter type="point"><point name="position" value="0, 0, 1"/><rgb name="intensity" value="0.5"/></emitter>
    <emitter type="spot"><transform name="to_world"><translate z="2"/></transform><rgb name="intensity" value="6"/>
        <float name="cutoff_angle" value="40"/><float name="beam_width" value="20"/></emitter>
    <emitter type="directional"><vector name="direction" value="0, 0, -1"/><rgb name="irradiance" value="0.4"/></emitter>
    """ + ('<emitter type="constant"/>' if env else "")
    scene = load(tmp_path, emitters)
    wp.init()
    ds = DeviceScene(scene, "cpu")
    n = 400_000
    light, pdf, is_delta = (wp.zeros(n, dtype=wp.int32), wp.zeros(n, dtype=float), wp.zeros(n, dtype=wp.int32))
    wp.launch(selection_kernel, dim=n, inputs=[ds.scene, wp.uint32(5)], outputs=[light, pdf, is_delta])
    light, pdf, is_delta = light.numpy(), pdf.numpy(), is_delta.numpy()
    # the powers, from the scene description (over pi)
    lo, hi = scene.bounds()
    radius = 0.5 * np.linalg.norm(hi.astype(np.float64) - lo)
    area = float(np.sum(scene.light_power()))  # L A (luminance) of the emitter's two triangles
    a, b = math.radians(20), math.radians(40)
    # 2 pi times the falloff integrated over cos theta: the full cone, then the ramp (outer - theta) /
    # (outer - inner) over sin theta d theta (trapezoid rule, fine to 1e-9)
    thetas = np.linspace(a, b, 200001)
    g = (b - thetas) / (b - a) * np.sin(thetas)
    ramp = float(np.sum(0.5 * (g[1:] + g[:-1]) * np.diff(thetas)))
    spot_power = 2 * 6.0 * ((1 - math.cos(a)) + ramp)
    powers = np.array([area, 4 * 0.5, spot_power, 0.4 * radius ** 2])
    expected_share = powers / powers.sum() * (0.5 if env else 1.0)
    ids = light
    counts = np.array([np.sum(ids >= 0), np.sum(ids == LIGHT_DELTA_BASE), np.sum(ids == LIGHT_DELTA_BASE - 1),
                       np.sum(ids == LIGHT_DELTA_BASE - 2)])
    if env:
        counts = np.append(counts, np.sum(ids == -1))
        expected_share = np.append(expected_share, 0.5)
    p, stat, dof = chi2_test(counts, expected_share * n)
    print("counts", counts, "expected", expected_share * n, "p", p)
    assert p > 1e-3
    # a delta sample's pdf is its selection probability
    for k in range(3):
        sel = ids == LIGHT_DELTA_BASE - k
        assert np.all(is_delta[sel] == 1)
        assert np.allclose(pdf[sel], expected_share[1 + k], rtol=2e-3)
