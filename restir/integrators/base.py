"""Integrator protocol: allocate buffers once, then render frames; stages are timed by name."""
import numpy as np
import warp as wp

from ..timing import BufferRegistry, StageTimer


class Integrator:
    """Base class. Subclasses list STAGES and implement `render_frame` as a table of contents."""

    name = "base"
    STAGES: tuple[str, ...] = ()
    KERNELS: tuple = ()   # every kernel a frame launches; compiled before any stage is timed

    def __init__(self, dscene, settings: dict, device: str, slices: int | None = None):
        self.dscene = dscene
        self.settings = settings
        self.device = wp.get_device(device)
        self.slices = slices
        self.timer = StageTimer(self.device)
        for stage in self.STAGES:  # report stages in pipeline order, including unused ones
            self.timer.ms[stage] = 0.0
        self.buffers = BufferRegistry()
        cam = dscene.host.camera
        self.width, self.height = cam.width, cam.height
        self.num_pixels = self.width * self.height
        self.rays = 0
        self.reverse_launch = False  # debug: slices in reverse order (see parallel.launch_pixels)
        self.counters: dict[str, int] = {}  # NaN/inf and other events that must be seen, never hidden
        self.allocate()
        for k in self.KERNELS:
            wp.load_module(k.module, device=self.device)

    def camera(self, frame: int):
        """The device camera of `frame` (scripted motion from the settings, if any)."""
        from ..camera_motion import camera_pose

        motion = self.settings.get("camera_motion", "none")
        if motion == "none":
            return self.dscene.camera
        host = self.dscene.host
        pose = camera_pose(host.camera.to_world, host.bounds(), motion, self.settings["camera_speed"], frame)
        return self.dscene.camera_at(pose)

    def buffer(self, name: str, dtype, shape=None):
        a = wp.zeros(shape or self.num_pixels, dtype=dtype, device=self.device)
        self.buffers.add(name, a)
        return a

    def count(self, name: str, per_pixel) -> None:
        self.counters[name] = self.counters.get(name, 0) + int(per_pixel.numpy().sum(dtype=np.int64))

    def allocate(self) -> None:
        raise NotImplementedError

    def render_frame(self, frame: int) -> tuple[np.ndarray, np.ndarray]:
        """Returns (mean, variance) per pixel over this frame's samples, each (H, W, 3)."""
        raise NotImplementedError
