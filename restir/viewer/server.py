"""`restir view`: a local web viewer (viser) over a LiveRender.

The browser sends its camera on every move; a loop in the calling thread renders the current
method from the camera of the browser that moved last and sends the frame back to every open
tab as the page's background image. While the camera moves (for MOVING_S after the last
update) the film's sides drop to MOVING_SCALE so that frames keep coming; once it stops they
rise again. Each size keeps its own integrator and history (live.py).

The controls are made from the methods' typed settings (controls.py). A value the command line
would refuse is refused here with the same message, shown in the page, and the previous value
stays. With no tab open for IDLE_S the loop stops rendering until one connects.
"""
import copy
import math
import os
import threading
import time

import numpy as np

from ..config import ConfigError
from ..image_io import tonemap, write_exr, write_image
from .camera import browser_view, to_world_from_browser, view_as_text
from .controls import controls_for

MOVING_S = 0.35
MOVING_SCALE = 0.5
IDLE_S = 10.0
VIEWS = ("frame", "average", "denoised", "albedo", "normal", "error", "confidence", "shared samples")
FALSE_COLOUR = ("confidence", "shared samples")  # maps, shown in false colour without the exposure
STATS_EVERY_S = 0.5
MAX_FPS = 30.0  # frames sent at most per second: a small film renders faster than a browser can show


def false_colour(x: np.ndarray) -> np.ndarray:
    """Values in [0, 1] as linear RGB from dark blue through green to yellow (a map's view)."""
    x = np.clip(np.nan_to_num(x), 0.0, 1.0)[..., None]
    stops = np.array([[0.02, 0.02, 0.15], [0.0, 0.35, 0.45], [0.2, 0.7, 0.2], [1.0, 0.9, 0.1]])
    t = x * (len(stops) - 1)
    i = np.minimum(t.astype(int), len(stops) - 2)
    f = t - i
    return (stops[i[..., 0]] * (1 - f) + stops[i[..., 0] + 1] * f).astype(np.float32)


class CameraState:
    """The camera the frames follow: restir's camera-to-world, the vertical fov in degrees, the
    browser canvas's aspect, and when it last moved."""

    def __init__(self, to_world, fov_y, aspect):
        self.to_world, self.fov_y, self.aspect, self.moved_at = np.asarray(to_world, float), fov_y, aspect, 0.0


class Viewer:
    def __init__(self, live, host: str = "127.0.0.1", port: int = 8080, height: int | None = None,
                 exposure: float = 0.0, reference: np.ndarray | None = None, output_dir: str = ".", log=print):
        import viser

        self.live = live
        self.log = log
        self.lock = threading.RLock()          # the live: the render loop and the controls' callbacks
        self.stop_event = threading.Event()
        cam = live.scene.camera
        self.height = int(height or cam.height)
        self.camera = CameraState(live.start_pose, live.start_fov_y, cam.width / cam.height)
        self.exposure = exposure
        self.reference = reference
        self.output_dir = output_dir
        self.view = "average"
        self.paused, self.step_requested = False, False
        self.last_client_at = time.time()
        self.frame = None                      # the last ViewFrame
        self.frames_sent = 0
        self.camera_updates = 0                # camera messages from the pages
        self.saved: list[str] = []
        self.message = ""
        self._denoiser = None                  # (pose, size, Denoiser) of the last denoised view
        self._times: list[float] = []
        self._stats_at = 0.0
        self.server = viser.ViserServer(host=host, port=port, verbose=False)
        self.server.scene.set_up_direction(tuple(float(x) for x in cam.to_world[:3, 1]))
        self.server.on_client_connect(self._connect)
        self.server.on_client_disconnect(self._disconnect)
        self._build_gui()

    @property
    def url(self) -> str:
        host = self.server.get_host()
        return f"http://{'127.0.0.1' if host in ('0.0.0.0', '') else host}:{self.server.get_port()}"

    # ------------------------------------------------------------------ clients and the camera
    def _touch(self) -> None:
        self.last_client_at = time.time()

    async def _disconnect(self, client) -> None:  # async: run in viser's event loop, also while it stops
        self._touch()

    def _connect(self, client) -> None:
        self._touch()
        distance = float(np.linalg.norm(np.subtract(*self.live.scene.bounds()))) * 0.5 or 1.0
        position, target, up = browser_view(self.camera.to_world, distance)
        client.camera.up_direction = tuple(up)
        client.camera.position = tuple(position)
        client.camera.look_at = tuple(target)
        client.camera.fov = math.radians(self.camera.fov_y)

        @client.camera.on_update
        def _(camera) -> None:
            self.camera_updates += 1
            pose = to_world_from_browser(camera.position, camera.wxyz)
            aspect = camera.aspect if camera.image_height else self.camera.aspect
            with self.lock:
                # the page echoes its camera with float noise, and its canvas size moves with the
                # browser's pixel-ratio tuning: only a visible change counts as a move
                if not (np.allclose(pose, self.camera.to_world, atol=1e-6) and
                        abs(math.degrees(camera.fov) - self.camera.fov_y) < 1e-4 and
                        abs(aspect / self.camera.aspect - 1) < 0.01):
                    self.camera = CameraState(pose, math.degrees(camera.fov), aspect)
                    self.camera.moved_at = time.time()
            self._touch()

    # ------------------------------------------------------------------ the controls
    def _build_gui(self) -> None:
        from ..integrators import METHODS

        gui = self.server.gui
        self.status = gui.add_markdown("starting")
        with gui.add_folder("View"):
            self.view_control = gui.add_dropdown("view", VIEWS, initial_value=self.view,
                                                 hint="the frame, the average since the camera or a setting last "
                                                      "changed, that average denoised (OIDN with albedo and normal), "
                                                      "the first hit's albedo or normal, the relative error "
                                                      "against the reference, each pixel's confidence M (ReSTIR "
                                                      "methods), or how many pixels hold the same sample (1 dark: "
                                                      "its own; bright: taken over by many neighbours)")
            self.exposure_control = gui.add_slider("exposure", min=-8.0, max=8.0, step=0.25,
                                                   initial_value=self.exposure, hint="stops")
            self.pause_control = gui.add_checkbox("pause", False, hint="stop rendering new frames")
            step = gui.add_button("step", hint="one frame while paused")
            save = gui.add_button("save frame and camera",
                                  hint=f"the shown average as EXR and PNG in {os.path.abspath(self.output_dir)}, and "
                                       "the camera as a <sensor> element and as Python")
            reference = gui.add_button("path-traced reference here",
                                       hint="render the path tracer from this camera (64 frames) as the reference of "
                                            "the error view")
        with gui.add_folder("Method"):
            self.method_control = gui.add_dropdown("method", tuple(METHODS), initial_value=self.live.method)
            self.spp_control = gui.add_number("spp", self.live.config.spp or 1, min=1, step=1,
                                              hint="samples per pixel per frame")
            self.settings_folder = gui.add_folder("settings")
            self.setting_controls: list = []
        self._fill_settings()
        self.view_control.on_update(lambda _: setattr(self, "view", self.view_control.value))
        self.exposure_control.on_update(lambda _: setattr(self, "exposure", float(self.exposure_control.value)))
        self.pause_control.on_update(lambda _: setattr(self, "paused", bool(self.pause_control.value)))
        step.on_click(lambda _: setattr(self, "step_requested", True))
        save.on_click(lambda _: self.save())
        reference.on_click(lambda _: self.compute_reference())
        self.method_control.on_update(lambda _: self._change(lambda: self.live.set_method(self.method_control.value),
                                                             rebuild_controls=True))
        self.spp_control.on_update(lambda _: self._change(lambda: self.live.set_render(spp=int(self.spp_control.value))))

    def _fill_settings(self) -> None:
        gui = self.server.gui
        for c in self.setting_controls:
            c.remove()
        self.setting_controls = []
        current = self.live.settings
        with self.settings_folder:
            for ctl in controls_for(self.live.integrator_class()):
                value = current.get(ctl.key, ctl.default)
                label = ctl.key + (" *" if ctl.static else "")
                if ctl.widget == "checkbox":
                    h = gui.add_checkbox(label, bool(value), hint=ctl.hint)
                elif ctl.widget in ("integer", "number"):
                    h = gui.add_number(label, value, step=1 if ctl.widget == "integer" else None, hint=ctl.hint)
                else:
                    h = gui.add_text(label, str(value), hint=ctl.hint)
                h.on_update(self._setting_callback(ctl, h))
                self.setting_controls.append(h)

    def _setting_callback(self, ctl, handle):
        def cb(_) -> None:
            value = handle.value
            previous = self.live.settings.get(ctl.key, ctl.default)
            if value == previous:
                return
            if not self._change(lambda: self.live.set_setting(ctl.key, value if ctl.widget != "text" else str(value)),
                                what=f"{ctl.key} = {value}" + (": static, other kernels (compiled the first time)"
                                                              if ctl.static else ": the history restarts")):
                handle.value = previous  # refused: the previous value back in the page
        return cb

    def _change(self, apply, rebuild_controls: bool = False, what: str = "") -> bool:
        """Apply a change under the lock; a refusal is shown (the command line's message) and
        changes nothing."""
        with self.lock:
            try:
                apply()
            except ConfigError as e:
                self.message = f"refused: {e}"
                self.log(f"restir view: {self.message}")
                if rebuild_controls:
                    self.method_control.value = self.live.method
                return False
            self.message = what
            self._denoiser = None
            if rebuild_controls:
                self._fill_settings()
        return True

    # ------------------------------------------------------------------ actions
    def save(self) -> list[str]:
        """The shown average (EXR and PNG) and the camera (printed, and a text file beside)."""
        with self.lock:
            if self.frame is None:
                self.message = "nothing rendered yet"
                return []
            image, pose, fov_y = self.frame.average, self.frame_pose, self.frame_fov
            os.makedirs(self.output_dir, exist_ok=True)
            stem = os.path.join(self.output_dir, f"restir_view_{len(self.saved):03d}")
            write_exr(stem + ".exr", image)
            write_image(stem + ".png", image, self.exposure)
            xml, py = view_as_text(pose, fov_y)
            with open(stem + ".camera.txt", "w") as f:
                f.write(xml + "\n\n" + py + "\n")
            self.saved += [stem + ".exr", stem + ".png", stem + ".camera.txt"]
            self.message = f"saved {stem}.exr, .png and .camera.txt"
            self.log(f"restir view: {self.message}\n{xml}\n{py}")
            return self.saved[-3:]

    def compute_reference(self, frames: int = 64) -> None:
        from ..api import render

        with self.lock:
            if self.frame is None:
                return
            h, w = self.frame.image.shape[:2]
            scene = copy.copy(self.live.scene)
            scene.camera = self.live.camera(w, h, self.frame_fov, self.frame_pose)
            self.message = "rendering the path-traced reference..."
            self.reference = render(scene, method="pt", spp=4, frames=frames, seed=7,
                                    device=self.live.config.device).image
            self.message = f"reference: the path tracer, {4 * frames} spp, from this camera"

    # ------------------------------------------------------------------ the loop
    def shown(self) -> np.ndarray:
        """The image of the current view, linear (H, W, 3)."""
        f = self.frame
        if self.view == "frame":
            return f.image
        if self.view == "denoised":
            return self._denoised(f.average)
        if self.view in ("albedo", "normal"):
            aov = self.live.aovs(self.frame_pose, f.image.shape[1], f.image.shape[0], self.frame_fov)[self.view]
            return 0.5 * (aov + 1.0) if self.view == "normal" else aov
        if self.view in FALSE_COLOUR:
            maps = self.live.reuse_maps()
            if maps is None:
                self.message = f"{self.view}: the path tracer keeps no reservoirs"
                return f.average
            if self.view == "confidence":
                m = maps["confidence"]
                return false_colour(m / max(float(m.max()), 1e-9))
            shared = maps["shared"]  # 1 (its own sample) to many, on a log scale
            return false_colour(np.log2(np.maximum(shared, 1.0)) / max(np.log2(max(float(shared.max()), 2.0)), 1e-9))
        if self.view == "error":
            ref = self.reference
            if ref is None or ref.shape != f.average.shape:
                self.message = "error view: no reference of this size (press 'path-traced reference here')"
                return f.average
            return np.abs(f.average - ref) / (np.abs(ref) + 1e-2)
        return f.average

    def _denoised(self, image):
        from ..compare.denoise import Denoiser, require_oidn

        key = (self.frame_pose.tobytes(), image.shape)
        if self._denoiser is None or self._denoiser[0] != key:
            try:
                require_oidn()
                aux = self.live.aovs(self.frame_pose, image.shape[1], image.shape[0], self.frame_fov)
                self._denoiser = (key, Denoiser.from_guides(aux, self.live.config.device))
            except ConfigError as e:
                self.message = str(e)
                return image
        return self._denoiser[1](image)

    def render_once(self) -> bool:
        """Render and send one frame, if there is anything to render for; whether one was."""
        now = time.time()
        if not self.server.get_clients():
            if now - self.last_client_at > IDLE_S:
                return False
        else:
            self._touch()
        if self.paused and not self.step_requested:
            return False
        self.step_requested = False
        with self.lock:
            cam = self.camera
            moving = now - cam.moved_at < MOVING_S
            h = max(8, int(round(self.height * (MOVING_SCALE if moving else 1.0))))
            w = max(8, int(round(h * cam.aspect)))
            self.frame = self.live.render(cam.to_world, w, h, cam.fov_y)
            self.frame_pose, self.frame_fov = cam.to_world, cam.fov_y
            image = self.shown()
        rgb = tonemap(image, self.exposure if self.view not in ("albedo", "normal", "error", *FALSE_COLOUR) else 0.0)
        self.server.scene.set_background_image(rgb, format="jpeg", jpeg_quality=90)
        self.frames_sent += 1
        self._times.append(time.time())
        self._times = [t for t in self._times if t > time.time() - 2.0]
        if time.time() - self._stats_at > STATS_EVERY_S:
            self._stats_at = time.time()
            self.status.content = self.stats_markdown(moving)
        return True

    def stats_markdown(self, moving: bool = False) -> str:
        f = self.frame
        st = f.stats
        fps = (len(self._times) - 1) / (self._times[-1] - self._times[0]) if len(self._times) > 1 else 0.0
        stages = " · ".join(f"{k} {v:.1f}" for k, v in st["stage_ms"].items())
        lines = [f"**{st['method']}** {st['width']}x{st['height']}{' (moving)' if moving else ''}",
                 f"{fps:.1f} frames/s · {st['frame_ms']:.0f} ms/frame · {st['rays_per_second'] / 1e6:.1f} Mrays/s · "
                 f"{st['bytes_per_pixel'].get('total', 0):.0f} B/px",
                 f"ms: {stages}", f"average of {f.frames_averaged} frames"]
        if self.view in FALSE_COLOUR:
            maps = self.live.reuse_maps()
            if maps is not None:
                m, shared = maps["confidence"], maps["shared"]
                with_sample = shared > 0
                lines.append(f"mean M {m.mean():.1f} (max {m.max():.0f}) · "
                             f"{(shared > 1).sum() / max(with_sample.sum(), 1):.0%} of the samples shared, "
                             f"the most by {shared.max():.0f} pixels")
        if self.message:
            lines.append(f"_{self.message}_")
        return "  \n".join(lines)

    def run(self) -> None:
        """Render until stop() or Ctrl-C (which the caller turns into exit status 130)."""
        try:
            while not self.stop_event.is_set():
                t0 = time.time()
                if not self.render_once():
                    self.stop_event.wait(0.05)
                else:
                    self.stop_event.wait(max(0.0, 1.0 / MAX_FPS - (time.time() - t0)))
        finally:
            self.server.stop()

    def stop(self) -> None:
        self.stop_event.set()
