"""The viewer's parts without a browser (restir/viewer/): the controls made from the typed
settings, the camera conventions between the browser and restir, and the live render that renders
frames from a given camera (its history kept, its average reset on a move, its settings checked
as the command line checks them)."""
import math

import numpy as np
import pytest

import restir
from restir.config import ConfigError
from restir.integrators import METHODS
from restir.scene.transforms import look_at
from restir.viewer.camera import browser_view, fov_axis_y, quaternion_matrix, to_world_from_browser, view_as_text
from restir.viewer.controls import controls_for
from restir.viewer.live import LiveRender


@pytest.mark.parametrize("method", list(METHODS))
def test_the_controls_list_every_setting_of_every_method(method):
    """Every `--set` setting but the fault injections, with its default, documentation and kind."""
    cls = METHODS[method]
    controls = {c.key: c for c in controls_for(cls)}
    expected = {k for k in cls.SETTINGS if not k.startswith("debug.")}
    assert set(controls) == expected
    static = set(cls.Settings.static_keys())
    for key, c in controls.items():
        assert c.default == cls.SETTINGS[key] and c.doc == cls.SETTINGS_DOC[key] and c.static == (key in static)
        assert c.widget == {bool: "checkbox", int: "integer", float: "number", str: "text"}[type(c.default)]
    # every runtime setting is among them
    assert {k for k in cls.SETTINGS if k not in static and not k.startswith("debug.")} <= set(controls)


def test_the_browsers_camera_maps_to_restirs_and_back():
    """viser's camera (OpenCV: +X right, +Y down, +Z forward) and restir's (Mitsuba: +X left, +Y
    up, +Z forward): the same view axis, right and down turned into left and up."""
    rng = np.random.default_rng(1)
    for _ in range(20):
        q = rng.normal(size=4)
        q /= np.linalg.norm(q)
        pos = rng.normal(size=3)
        r = quaternion_matrix(q)
        m = to_world_from_browser(pos, q)
        np.testing.assert_allclose(m[:3, 2], r[:, 2], atol=1e-12)   # forward
        np.testing.assert_allclose(m[:3, 1], -r[:, 1], atol=1e-12)  # up = -down
        np.testing.assert_allclose(m[:3, 0], -r[:, 0], atol=1e-12)  # left = -right
        assert np.linalg.det(m[:3, :3]) == pytest.approx(1.0)
        p, target, up = browser_view(m, 2.0)
        np.testing.assert_allclose(target - p, 2.0 * r[:, 2], atol=1e-12)
        np.testing.assert_allclose(up, -r[:, 1], atol=1e-12)


def test_the_saved_view_rebuilds_the_pose():
    m = look_at([1.0, 2.0, -3.0], [0.2, 0.5, 0.0], [0.0, 1.0, 0.0])
    xml, py = view_as_text(m, 37.5)
    assert '<float name="fov" value="37.5"/>' in xml and '<string name="fov_axis" value="y"/>' in xml
    scope = {}
    code = py.replace("scene.camera.", "cam_")
    exec(code, scope)
    np.testing.assert_allclose(scope["cam_to_world"], m, atol=1e-5)
    assert scope["cam_fov"] == 37.5 and scope["cam_fov_axis"] == "y"


def test_the_vertical_field_of_view_of_each_axis():
    assert fov_axis_y(40.0, "y", 200, 100) == 40.0
    t = math.tan(math.radians(20.0))
    assert fov_axis_y(40.0, "x", 200, 100) == pytest.approx(math.degrees(2 * math.atan(t / 2)))
    assert fov_axis_y(40.0, "smaller", 200, 100) == 40.0
    assert fov_axis_y(40.0, "larger", 200, 100) == pytest.approx(fov_axis_y(40.0, "x", 200, 100))
    assert fov_axis_y(40.0, "diagonal", 200, 100) == pytest.approx(math.degrees(2 * math.atan(t / math.sqrt(5))))


@pytest.fixture(scope="module")
def live():
    return LiveRender(restir.load_scene("builtin:cornell-box"), "restir-pt")


def test_the_session_keeps_the_history_and_averages_until_the_camera_moves(live):
    pose = live.start_pose
    frames = [live.render(pose, 24, 16) for _ in range(3)]
    assert [f.frames_averaged for f in frames][-2:] == [2, 3]
    assert len(live.integrators) == 1  # one integrator, its history carried from frame to frame
    integ = next(iter(live.integrators.values()))
    moved = pose.copy()
    moved[0, 3] += 0.01
    f = live.render(moved, 24, 16)
    assert f.frames_averaged == 1 and next(iter(live.integrators.values())) is integ
    assert f.image.shape == (16, 24, 3) and np.all(np.isfinite(f.image)) and f.image.mean() > 0
    assert set(f.stats["stage_ms"]) <= set(integ.STAGES) and f.stats["bytes_per_pixel"]["total"] > 0
    live.render(moved, 12, 8)  # the moving size: another integrator; the first is kept
    assert len(live.integrators) == 2 and live.integrators[(24, 16, round(live.start_fov_y, 4))] is integ


def test_a_refused_setting_keeps_the_previous_value_with_the_command_lines_message(live):
    live.set_setting("temporal.cap", "3")
    with pytest.raises(ConfigError, match="not a float"):
        live.set_setting("temporal.cap", "fast")
    with pytest.raises(ConfigError, match="emission.rays must be in"):
        live.set_setting("emission.rays", 0)
    with pytest.raises(ConfigError, match="unknown setting 'nope'"):
        live.set_setting("nope", 1)
    assert live.settings == {"temporal.cap": 3.0}
    assert live.set_setting("stages.split", "true") is True  # static: other kernels
    with pytest.raises(ConfigError, match="unknown method"):
        live.set_method("nope")
    live.set_method("pt")
    assert live.method == "pt" and live.settings == {} and not live.integrators
    assert live.render(live.start_pose, 24, 16).stats["method"] == "pt"


def test_the_reuse_maps_count_the_pixels_that_share_a_sample():
    """Spatial reuse hands samples to neighbours: some samples are then held by several pixels.
    Without reuse every pixel keeps its own (seeds are per pixel), so none is shared; the path
    tracer has no reservoirs."""
    scene = restir.load_scene("builtin:cornell-box")
    for settings, shared_expected in (({}, True), ({"temporal": False, "spatial.rounds": 0}, False)):
        live = LiveRender(scene, "restir-pt", settings)
        for _ in range(4):
            live.render(live.start_pose, 24, 16)
        maps = live.reuse_maps()
        m, shared = maps["confidence"], maps["shared"]
        assert m.shape == shared.shape == (16, 24) and m.min() >= 0
        assert shared.min() >= 0 and np.all(shared == np.round(shared)) and (shared >= 1).any()
        assert (shared.max() > 1) == shared_expected, shared.max()
        if shared_expected:
            assert m.max() > 1  # temporal and spatial reuse add confidence
    live = LiveRender(scene, "pt")
    live.render(live.start_pose, 8, 8)
    assert live.reuse_maps() is None
