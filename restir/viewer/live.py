"""Continuous rendering for the viewer, without the browser: a scene on the device, one method's
integrator at a time, and frames rendered from whatever camera the caller gives.

`LiveRender.render(to_world, width, height, fov_y)` renders one frame of the current method
from that pose. The integrator lives on while the film size, the field of view and the settings
stay: temporal reuse then sees the real camera path, frame after frame (the methods'
reprojection follows the camera; nothing restarts). The scene is uploaded once; an integrator is
built for each film size asked for (the viewer drops the resolution while the camera moves) and
kept, so that going back to a size keeps that size's history.

Settings: `set_method` and `set_setting` check a change as the command line would (the same
ConfigError) before anything changes, and keep the previous value when it is refused. Any
accepted change rebuilds the integrators. A static setting selects other kernels, compiled the
first time they are used; a runtime setting only restarts the history, because the methods pack
settings into their kernel parameters when they allocate.

The frame's numbers (`ViewFrame.stats`): milliseconds per stage and in all, rays per second and
bytes per pixel, as the integrator counts them.
"""
import copy
import dataclasses
import time

import numpy as np

from ..api import check_device, make_integrator, method_settings
from ..config import ConfigError, RenderConfig, parse_value
from ..scene.upload import DeviceScene
from .camera import fov_axis_y

MAX_INTEGRATORS = 3  # film sizes kept at once (the moving and the still one, and one in between)


@dataclasses.dataclass
class ViewFrame:
    image: np.ndarray        # this frame, (H, W, 3) linear RGB
    average: np.ndarray      # the mean of the frames since the camera or a setting last changed
    frames_averaged: int
    stats: dict              # ms per stage and in all, rays per second, bytes per pixel, notes


class LiveRender:
    def __init__(self, scene, method: str = "restir-pt", settings: dict | None = None, device: str = "cpu",
                 spp: int = 1, max_depth: int | None = None, seed: int = 0, on_compile=None):
        self.scene = scene
        self.config = RenderConfig(method=method, spp=spp, max_depth=max_depth, seed=seed, device=device,
                                   settings=dict(settings or {}))
        self.config.validate()
        check_device(self.config)
        method_settings(scene, self.config)  # refused here, before the upload
        self.on_compile = on_compile
        self.dscene = DeviceScene(scene, device)
        cam = scene.camera
        self.start_pose = np.asarray(cam.to_world, float).copy()
        self.start_fov_y = fov_axis_y(cam.fov, cam.fov_axis, cam.width, cam.height)
        self.integrators: dict = {}  # (width, height, fov) -> integrator, most recently used last
        self.frame_index = 0
        self._last = None            # (key, pose) of the last frame: the running average's
        self._sum, self._count = None, 0
        self._aovs = None            # (key, pose bytes, generation, guides): one view's, kept while it stands
        self._maps = None            # (frame_index, maps) of the last frame
        self.generation = 0          # counts rebuilds (a setting or the method changed)

    # ------------------------------------------------------------------ settings
    @property
    def method(self) -> str:
        return self.config.method

    @property
    def settings(self) -> dict:
        return dict(self.config.settings)

    def integrator_class(self):
        return method_settings(self.scene, self.config)[0]

    def set_method(self, method: str, settings: dict | None = None) -> None:
        """Switch the method (its settings reset to `settings`, default none); refused (a
        ConfigError, nothing changed) as the command line refuses it."""
        self._apply(dataclasses.replace(self.config, method=method, settings=dict(settings or {})))

    def set_setting(self, key: str, value) -> bool:
        """Set one `--set` setting of the current method (a string is parsed by the default's
        type, as on the command line). Returns whether it is static (other kernels). Refused
        (a ConfigError, the previous value kept) as the command line refuses it."""
        cls = self.integrator_class()
        if key not in cls.SETTINGS:
            raise ConfigError(f"unknown setting '{key}' (known: {', '.join(sorted(cls.SETTINGS)) or 'none'})")
        if isinstance(value, str):
            value = parse_value(value, cls.SETTINGS[key])
        self._apply(dataclasses.replace(self.config, settings={**self.config.settings, key: value}))
        return key in cls.Settings.static_keys()

    def set_render(self, **fields) -> None:
        """spp, max_depth or seed (RenderConfig's meanings), checked as `restir render` checks them."""
        unknown = set(fields) - {"spp", "max_depth", "seed"}
        if unknown:
            raise ConfigError(f"not a viewer render setting: {', '.join(sorted(unknown))}")
        self._apply(dataclasses.replace(self.config, **fields))

    def _apply(self, config: RenderConfig) -> None:
        config.validate()
        method_settings(self.scene, config)  # raises before anything changes
        self.config = config
        self.integrators.clear()
        self.generation += 1
        self._last = None

    # ------------------------------------------------------------------ frames
    def camera(self, width: int, height: int, fov_y: float, to_world=None):
        """The scene's camera (a copy) at that film size and vertical field of view, and pose."""
        cd = copy.copy(self.scene.camera)
        cd.width, cd.height, cd.fov, cd.fov_axis = int(width), int(height), float(fov_y), "y"
        if to_world is not None:
            cd.to_world = np.asarray(to_world, float)
        return cd

    def _integrator(self, width: int, height: int, fov_y: float):
        key = (int(width), int(height), round(float(fov_y), 4))
        integ = self.integrators.pop(key, None)
        if integ is None:
            dscene = self.dscene.with_camera(self.camera(*key))
            cfg = dataclasses.replace(self.config, width=key[0], height=key[1])
            integ = make_integrator(dscene.host, cfg, self.on_compile, dscene=dscene)
            while len(self.integrators) >= MAX_INTEGRATORS:
                self.integrators.pop(next(iter(self.integrators)))
        self.integrators[key] = integ  # most recently used last
        return key, integ

    def render(self, to_world, width: int, height: int, fov_y: float | None = None) -> ViewFrame:
        """One frame from camera-to-world `to_world` (restir's convention), at width x height
        with vertical field of view fov_y (degrees; the scene's by default)."""
        fov_y = self.start_fov_y if fov_y is None else fov_y
        if not (0.0 < fov_y < 180.0):
            raise ConfigError(f"the field of view must be in (0, 180) degrees, not {fov_y}")
        pose = np.asarray(to_world, float)
        key, integ = self._integrator(width, height, fov_y)
        before = dict(integ.timer.ms)
        rays_before = integ.rays
        integ.view_pose = pose
        t0 = time.perf_counter()
        mean, _ = integ.render_frame(self.frame_index)
        wall_ms = (time.perf_counter() - t0) * 1e3
        self.frame_index += 1
        same = self._last is not None and self._last[0] == (key, self.generation) and np.array_equal(self._last[1], pose)
        if same:
            self._sum += mean
            self._count += 1
        else:
            self._sum, self._count = mean.astype(np.float64), 1
        self._last = ((key, self.generation), pose)
        stage_ms = {k: v - before.get(k, 0.0) for k, v in integ.timer.ms.items() if v - before.get(k, 0.0) > 0}
        total = sum(stage_ms.values())
        rays = integ.rays - rays_before
        stats = {"method": self.method, "width": key[0], "height": key[1], "frame_ms": wall_ms,
                 "stage_ms": stage_ms, "rays_per_second": rays / (total / 1e3) if total > 0 else 0.0,
                 "bytes_per_pixel": integ.buffers.per_pixel(integ.num_pixels), "notes": list(integ.notes)}
        return ViewFrame(mean, (self._sum / self._count).astype(np.float32), self._count, stats)

    def aovs(self, to_world, width: int, height: int, fov_y: float | None = None) -> dict:
        """The albedo and normal at the first hit from that view (the denoiser's guides),
        computed once while the view stands."""
        from ..aov import AOV_SAMPLES, compute_aovs

        fov_y = self.start_fov_y if fov_y is None else fov_y
        pose = np.asarray(to_world, float)
        key, integ = self._integrator(width, height, fov_y)
        tag = (key, pose.tobytes(), self.generation)
        if self._aovs is None or self._aovs[0] != tag:
            integ.view_pose = pose
            self._aovs = (tag, compute_aovs(integ, ("albedo", "normal"), AOV_SAMPLES))
        return self._aovs[1]

    def reuse_maps(self) -> dict | None:
        """For the methods with reservoirs, after the last frame: each pixel's confidence M, and
        how many pixels of the frame hold the very same sample (1: its own; more: neighbours
        took it over, which is what makes ReSTIR's blotches). None for the path tracer.

        A sample's identity: a path's random seed and reconnection vertex (ReSTIR PT, Suffix
        ReSTIR), or the light point (ReSTIR DI). Pixels without a sample (W = 0) count 0."""
        if self._last is None:
            return None
        if self._maps is not None and self._maps[0] == self.frame_index:
            return self._maps[1]
        key = self._last[0][0]
        integ = self.integrators.get(key)
        res = getattr(integ, "reservoirs", None)
        if res is None:
            return None
        a = res.previous.numpy()  # the frame's final reservoirs: the history of the next frame
        h, w = key[1], key[0]
        has = (a["W"] > 0) & (a["M"] > 0)
        if "seed" in a.dtype.names:
            ident = np.column_stack([a["seed"].astype(np.float64), a["rc_tri"].astype(np.float64),
                                     a["rc_bary"].reshape(len(a), -1).astype(np.float64)])
        else:
            ident = np.column_stack([a["light_tri"].astype(np.float64), a["light_y"].reshape(len(a), -1)])
        shared = np.zeros(len(a))
        if has.any():
            _, inverse, counts = np.unique(ident[has], axis=0, return_inverse=True, return_counts=True)
            shared[has] = counts[inverse.reshape(-1)]
        maps = {"confidence": a["M"].reshape(h, w).astype(np.float32), "shared": shared.reshape(h, w)}
        self._maps = (self.frame_index, maps)
        return maps
