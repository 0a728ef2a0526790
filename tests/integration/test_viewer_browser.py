"""`restir view` in Debian's Chromium through Selenium (tests/browser.py), with the viewer's server
in this process (a thread) so that the test can read what it rendered and sent.

The page loads and frames arrive; a drag in the canvas moves the camera and changes the image;
switching the method and setting a value in the page change what is rendered (and a value the
command line refuses is refused with its message, the previous value kept); the confidence, shared
samples and denoised views;
saving writes the shown average (EXR and PNG, equal to it) and a camera that reproduces the
view, whose path-traced render agrees with the saved image; two tabs at once; a closed tab stops
the rendering. The command itself: a scene that fails to load is a one-line error before any
server starts, and Ctrl-C ends the server with status 130 and no traceback."""
import os
import signal
import socket
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

import restir
from restir.image_io import read_exr
from restir.integrators import METHODS
from restir.viewer import server as view_server
from restir.viewer.server import Viewer
from restir.viewer.live import LiveRender
from tests.browser import chromium

pytest.importorskip("viser")
pytest.importorskip("selenium")

HEIGHT = 24
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def wait_for(condition, timeout=60.0, what="the condition"):
    t_end = time.time() + timeout
    while time.time() < t_end:
        if condition():
            return
        time.sleep(0.1)
    raise AssertionError(f"timed out waiting for {what() if callable(what) else what}")


@pytest.fixture
def viewer(tmp_path):
    live = LiveRender(restir.load_scene("builtin:cornell-box"), "restir-pt")
    v = Viewer(live, port=free_port(), height=HEIGHT, output_dir=str(tmp_path), log=lambda *a: None)
    thread = threading.Thread(target=v.run, daemon=True)
    thread.start()
    yield v
    v.stop()
    thread.join(20)


@pytest.fixture
def browser():
    drivers = []

    def open_page(url):
        d = chromium()
        drivers.append(d)
        d.get(url)
        return d

    yield open_page
    for d in drivers:
        d.quit()


def control(driver, label):
    """The input of the control labelled `label` (viser labels its inputs with <label for>)."""
    from selenium.webdriver.common.by import By

    path = f"//label[normalize-space(.)='{label}']"
    wait_for(lambda: driver.find_elements(By.XPATH, path), 30, f"the control '{label}' in the page")
    return driver.find_element(By.ID, driver.find_element(By.XPATH, path).get_attribute("for"))


def choose(driver, label, option):
    from selenium.webdriver.common.by import By

    control(driver, label).click()
    wait_for(lambda: any(o.text == option for o in driver.find_elements(By.XPATH, "//*[@role='option']")),
             10, f"the option {option}")
    next(o for o in driver.find_elements(By.XPATH, "//*[@role='option']") if o.text == option).click()


def type_into(driver, label, text):
    from selenium.webdriver.common.keys import Keys

    field = control(driver, label)
    field.send_keys(Keys.CONTROL, "a")
    field.send_keys(text, Keys.TAB)  # leaving the field sends the value (and lets the page show a reset)


def click(driver, text):
    from selenium.webdriver.common.by import By

    driver.find_element(By.XPATH, f"//button[normalize-space(.)='{text}']").click()


def frames_after(v, n=3, timeout=60.0):
    start = v.frames_sent
    wait_for(lambda: v.frames_sent >= start + n, timeout, f"{n} more frames")


def test_frames_arrive_and_a_drag_moves_the_camera_and_the_image(viewer, browser):
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.by import By

    d = browser(viewer.url)
    wait_for(lambda: viewer.frames_sent > 3 and viewer.camera_updates > 0, 60, "frames and the page's camera")
    # the page's first camera message counts as a move: the full size follows once it settles
    wait_for(lambda: viewer.frame.image.shape[:2] == (HEIGHT, round(HEIGHT * viewer.camera.aspect))
             and viewer.frame.frames_averaged > 3, 30, "the full size at the page's aspect")
    assert viewer.frame.image.mean() > 0.01
    before_pose, before_image = viewer.camera.to_world.copy(), viewer.frame.average.copy()
    canvas = max(d.find_elements(By.TAG_NAME, "canvas"), key=lambda c: c.size["width"] * c.size["height"])
    ActionChains(d).move_to_element(canvas).click_and_hold().move_by_offset(60, 15).release().perform()
    wait_for(lambda: not np.allclose(viewer.camera.to_world, before_pose), 20, "the camera to move")
    frames_after(viewer)
    wait_for(lambda: viewer.frame.image.shape == before_image.shape, 20,
             lambda: f"the full size back once the camera stopped ({viewer.frame.image.shape} now, "
                     f"{before_image.shape} before; last move {time.time() - viewer.camera.moved_at:.1f} s ago)")
    moved = viewer.camera.to_world
    assert not np.allclose(moved[:3, 2], before_pose[:3, 2])  # turned, not just shifted
    assert np.abs(viewer.frame.average - before_image).mean() > 0.01


def test_switching_the_method_and_a_setting_change_the_frames(viewer, browser):
    d = browser(viewer.url)
    frames_after(viewer)
    assert "trace_temporal" in viewer.frame.stats["stage_ms"]
    choose(d, "method", "pt")
    wait_for(lambda: viewer.live.method == "pt", 30, "the method to switch")
    frames_after(viewer)
    assert viewer.frame.stats["method"] == "pt" and "trace_temporal" not in viewer.frame.stats["stage_ms"]
    wait_for(lambda: "**pt**" in viewer.status.content, 10, "the status to name pt")
    # a value the command line refuses: its message, and the previous value back in the page
    type_into(d, "emission.rays", "0")
    wait_for(lambda: viewer.message.startswith("refused: emission.rays must be in"), 20, "the refusal")
    assert viewer.live.settings == {}
    default = str(METHODS["pt"].SETTINGS["emission.rays"])
    wait_for(lambda: control(d, "emission.rays").get_attribute("value") == default, 20,
             lambda: f"the previous value back (the page shows {control(d, 'emission.rays').get_attribute('value')})")
    type_into(d, "emission.rays", "2")
    wait_for(lambda: viewer.live.settings == {"emission.rays": 2}, 20, "the setting to apply")
    frames_after(viewer)
    assert viewer.frame.stats["method"] == "pt"


def test_the_confidence_and_denoised_views(viewer, browser):
    d = browser(viewer.url)
    frames_after(viewer)
    choose(d, "view", "confidence")
    wait_for(lambda: "mean M" in viewer.status.content, 20, "the confidence numbers in the status")
    choose(d, "view", "shared samples")
    wait_for(lambda: viewer.view == "shared samples", 20, "the view to switch")
    frames_after(viewer)
    pytest.importorskip("pyoidn")
    choose(d, "view", "denoised")
    wait_for(lambda: viewer.view == "denoised", 20, "the view to switch")
    frames_after(viewer)
    assert "denoise" not in viewer.message.lower()  # no refusal (OIDN is installed)


def test_save_writes_the_shown_average_and_a_camera_that_reproduces_it(viewer, browser, tmp_path):
    d = browser(viewer.url)
    frames_after(viewer, 20)
    control(d, "pause").click()
    wait_for(lambda: viewer.paused, 10, "the pause")
    time.sleep(0.5)  # a frame in flight finishes
    shown = viewer.frame.average.copy()
    click(d, "save frame and camera")
    wait_for(lambda: len(viewer.saved) == 3, 20, "the files")
    exr, png, cam = viewer.saved
    np.testing.assert_array_equal(read_exr(exr), shown)
    assert os.path.getsize(png) > 0
    text = open(cam).read()
    assert "<sensor" in text and "look_at(" in text
    # the saved camera, set on the scene, renders (the path tracer) what the viewer averaged
    scene = restir.load_scene("builtin:cornell-box")
    exec(text.split("\n\n", 1)[1], {"scene": scene})
    h, w = shown.shape[:2]
    ref = restir.render(scene, method="pt", spp=16, frames=8, width=w, height=h, seed=5).image
    assert abs(shown.mean() / ref.mean() - 1) < 0.05, (shown.mean(), ref.mean())


def test_two_tabs_and_a_closed_tab_stops_the_rendering(viewer, browser, monkeypatch):
    monkeypatch.setattr(view_server, "IDLE_S", 2.0)
    first = browser(viewer.url)
    second = browser(viewer.url)
    wait_for(lambda: len(viewer.server.get_clients()) == 2, 30, "two tabs")
    frames_after(viewer)
    second.quit()
    frames_after(viewer)  # the first tab still gets frames
    first.quit()
    wait_for(lambda: not viewer.server.get_clients(), 30, "the tabs to close")
    time.sleep(view_server.IDLE_S + 1.0)
    n = viewer.frames_sent
    time.sleep(1.0)
    assert viewer.frames_sent == n  # no tab for IDLE_S: no more frames


def run_view(*args):
    return subprocess.Popen([sys.executable, "-m", "restir", "view", *args], stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True, cwd=ROOT)


def test_a_scene_that_fails_to_load_is_one_line_before_any_server(tmp_path):
    port = free_port()
    p = run_view(str(tmp_path / "missing.xml"), "--port", str(port))
    out, _ = p.communicate(timeout=120)
    assert p.returncode == 2 and "error:" in out and "Traceback" not in out and "http" not in out
    for bad, message in ((["--set", "nope=1"], "unknown setting 'nope'"), (["--port", "70000"], "not a port"),
                         (["--method", "nope"], "unknown method 'nope'"), (["--height", "0"], "height must be")):
        p = run_view("builtin:cornell-box", *bad)
        out, _ = p.communicate(timeout=120)
        assert p.returncode == 2 and message in out and "Traceback" not in out and "http" not in out, out


def test_ctrl_c_stops_the_server_with_status_130():
    port = free_port()
    p = run_view("builtin:cornell-box", "--port", str(port), "--height", str(HEIGHT))
    lines = []
    t_end = time.time() + 120
    while time.time() < t_end:
        line = p.stdout.readline()
        lines.append(line)
        if "open http" in line or not line:
            break
    assert any(f":{port}" in line for line in lines), lines
    p.send_signal(signal.SIGINT)
    out, _ = p.communicate(timeout=60)
    assert p.returncode == 130, "".join(lines) + out
    assert "Traceback" not in out and "stopped" in out
    with socket.socket() as s:  # nothing listens any more
        assert s.connect_ex(("127.0.0.1", port)) != 0
