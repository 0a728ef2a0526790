"""The Integrator base: everything a method shares besides its stages.

- allocation of named, registered buffers (memory stats per buffer),
- the frame loop: the camera of the frame (scripted motion), its samples, progress after each,
  the frame's moments accumulated on the device (film.py) and read once, the events read once,
- the stage runner: one timed launch per stage, its per-pixel events summed on the device
  (common/tally.py) into the counters,
- the stats of a render, read through `stats()` (the API never reads integrator internals).

A method lists its STAGES and KERNELS, implements `allocate` and `render_sample` (one sample of
every pixel: a flat table of contents of stage calls, returning the sample's radiance as a device
array). A method whose kernel averages several samples itself (the path tracer) implements
`render_samples` and `frame_moments` instead.
"""
import threading

import numpy as np
import warp as wp

from ..film import SampleFilm, film_add_kernel
from ..parallel import launch_pixels
from ..settings import Settings
from ..timing import BufferRegistry, StageTimer
from .common.emission_edges import small_emitters_kernel
from .common.events import COUNTER_NAMES, EV_RAYS, EV_SATURATED, EventCounts
from .common.mutations import Mutations
from .common.tally import TALLY_KERNELS, EventTally


COMPILE_NOTICE_S = 1.0  # loading cached kernels takes well under this; compiling takes 5-20 s


class FrameInterrupted(Exception):
    """A stop was asked for (Ctrl-C) while a frame rendered: the frame is dropped, unfinished."""


class Integrator:
    """Base class. Subclasses list STAGES and implement `render_sample` as a table of contents."""

    # The method protocol: what `restir info`, the config checks, compare and validate read of a
    # method (class attributes, so no render is needed to read them).
    name = "base"
    DESCRIPTION = ""        # one line for `restir info`
    Settings = Settings     # the method's settings dataclass (restir/settings.py)
    SETTINGS: dict = {}     # --set KEY=VALUE defaults, from Settings (made for each subclass)
    SETTINGS_DOC: dict = {}  # one line per setting, from Settings
    FIXED_MAX_DEPTH: int | None = None  # the only max_depth the method computes, or None: any
    MUTATIONS = Mutations((), {})  # fault injections of debug.mutation (common/mutations.py): none
    stage_prefix = ""  # prepended to stage names in the timings (a method used inside another: "di.")
    STAGES: tuple[str, ...] = ()
    KERNELS: tuple = ()   # every kernel a frame launches; compiled before any stage is timed

    def __init_subclass__(cls, **kw):
        super().__init_subclass__(**kw)
        cls.SETTINGS, cls.SETTINGS_DOC = cls.Settings.defaults(), cls.Settings.docs()

    @classmethod
    def check_settings(cls, settings) -> None:
        """Refuse settings the method cannot render (a ConfigError), before anything is built."""

    @staticmethod
    def motion_refusal(settings) -> str | None:
        """Why these settings cannot render an animated scene unbiased (their temporal reuse does
        not evaluate its history in the previous frame's scene), or None; api.method_settings refuses
        the render with it."""
        return None

    def __init__(self, dscene, settings: Settings, device: str, slices: int | None = None, on_compile=None):
        """on_compile: called with no argument when loading the kernels takes long (they are
        being compiled: the first run of a configuration; later runs load them from Warp's cache)."""
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
        self.stage_rays: dict[str, int] = {}  # rays traced per stage (a cost that does not depend on the machine)
        self.reverse_launch = False  # debug: slices in reverse order (see parallel.launch_pixels)
        self.counters: dict[str, int] = {}  # NaN/inf and other events that must be seen, never hidden
        self.notes: list[str] = []          # what the method changed of the request (shown and kept in stats)
        self.on_samples = None  # progress hook within a frame: on_samples(samples_done, spp), if set
        self.stop_requested = None  # if set, a callable: True drops the frame in flight (FrameInterrupted)
        self.view_pose = None  # a camera-to-world set from outside (the interactive viewer): wins over the motion
        self.events = self.buffer("events", EventCounts)  # per-stage scratch, summed into the tally
        self.tally = EventTally(self.device)  # the events' sums on the device, read once per frame
        self._film = None
        self.allocate()
        timer = threading.Timer(COMPILE_NOTICE_S, on_compile) if on_compile is not None else None
        if timer is not None:
            timer.daemon = True
            timer.start()
        try:
            for k in (*self.kernels(), *TALLY_KERNELS.values(), film_add_kernel, small_emitters_kernel):
                wp.load_module(k.module, device=self.device)
        finally:
            if timer is not None:
                timer.cancel()

    def kernels(self) -> tuple:
        """The kernels this configuration launches (compiled before the first frame)."""
        return self.KERNELS

    def camera(self, frame: int):
        """The device camera of `frame`: the viewer's pose when one is set, else the scripted
        motion of the settings, if any."""
        from ..camera_motion import camera_pose

        if self.view_pose is not None:
            return self.dscene.camera_at(self.view_pose)
        motion = self.settings.camera_motion
        if motion == "none":
            return self.dscene.camera
        host = self.dscene.host
        pose = camera_pose(host.camera.to_world, host.bounds(), motion, self.settings.camera_speed, frame)
        return self.dscene.camera_at(pose)

    def history_scene(self):
        """The scene a temporal pass evaluates the history's domain in: the previous sample's
        (`prev_scene`, which a method with temporal reuse keeps; the same as this one's unless the
        scene moved between them), or with temporal.previous_scene off (a biased switch), this one."""
        prev = getattr(self, "prev_scene", None)
        if prev is None or not getattr(self.settings, "temporal_previous_scene", True):
            return self.dscene.scene
        return prev

    def buffer(self, name: str, dtype, shape=None):
        a = wp.zeros(shape or self.num_pixels, dtype=dtype, device=self.device)
        self.buffers.add(name, a)
        return a

    def run_stage(self, stage: str, kernel, inputs: list, outputs: list, nonfinite: str = "nonfinite_weights",
                  new_call: bool = True, tally: bool = True) -> None:
        """Launch one stage over the pixels, timed. Every stage kernel takes `events` (8 bytes per
        pixel, common/events.py) as its last output; they are summed on the device (the tally,
        read into the counters once per frame), non-finite values under the name `nonfinite` (weights for resampling stages, outputs for
        stages that write radiance). new_call=False: a further part of the same run of the stage
        (its time adds to that run's). tally=False: a launch whose kernel adds its events to those
        already in `events`, summed with a later launch's."""
        key = self.stage_prefix + stage
        with self.timer.stage(key, new_call):
            launch_pixels(kernel, self.num_pixels, inputs, [*outputs, self.events], self.device, self.slices,
                          self.reverse_launch)
        if tally:
            self.tally.add(("stage", key, nonfinite), self.events)

    def collect_events(self) -> None:
        """Read the tally (once per frame: the one wait for the device's sums) into the counters,
        the rays per stage, and the method's own sums (`take_tally`). Per-pixel counts that
        saturated their packed fields (events.py) make the sums lower bounds: counted, so the stats
        say so."""
        for key, ev in self.tally.read().items():
            if ev[EV_SATURATED]:
                self.counters["saturated_counts"] = self.counters.get("saturated_counts", 0) + int(ev[EV_SATURATED])
            ev = ev[:EV_SATURATED]
            if key[0] != "stage":
                self.take_tally(key, ev)
                continue
            _, stage, nonfinite = key
            for i, name in enumerate((nonfinite,) + COUNTER_NAMES[1:]):
                self.counters[name] = self.counters.get(name, 0) + int(ev[i])
            self.stage_rays[stage] = self.stage_rays.get(stage, 0) + int(ev[EV_RAYS])

    def take_tally(self, key, sums: np.ndarray) -> None:
        """A method's own event sums (tally keys other than a stage's), once per frame."""
        raise KeyError(f"no owner for the event tally {key}")

    # ------------------------------------------------------------------ the frame loop
    @property
    def film(self) -> SampleFilm:
        if self._film is None:  # made on the first frame: a method that never renders one needs none
            self._film = SampleFilm(self, int(self.settings.spp))
        return self._film

    def render_frame(self, frame: int) -> tuple[np.ndarray, np.ndarray]:
        """One frame: (mean, variance) per pixel over its samples, each (H, W, 3)."""
        self.dscene.set_frame(frame)  # an animated scene's geometry and lights at this frame
        camera = self.camera(frame)
        spp = int(self.settings.spp)
        for begin, end in self.sample_batches(spp):
            self.render_samples(frame, begin, end, camera)
            if self.on_samples is not None:
                self.on_samples(end, spp)
            if self.stop_requested is not None and end < spp and self.stop_requested():
                raise FrameInterrupted(frame)
        self.collect_events()
        return self.frame_moments()

    def sample_batches(self, spp: int) -> list:
        """The frame's samples as [begin, end) ranges, progress reported after each: one by one."""
        return [(s, s + 1) for s in range(spp)]

    def render_samples(self, frame: int, begin: int, end: int, camera) -> None:
        if begin == 0:
            self.film.begin()
        for s in range(begin, end):
            self.film.add(self.render_sample(frame, s, camera))

    def render_sample(self, frame: int, sample: int, camera):
        """One sample of every pixel; its radiance, a device array (one vec3 per pixel) that stays
        unchanged until the next sample."""
        raise NotImplementedError

    def frame_moments(self) -> tuple[np.ndarray, np.ndarray]:
        return self.film.read((self.height, self.width, 3))

    @property
    def rays(self) -> int:
        """Rays traced so far, over every stage (a component's too: it shares stage_rays)."""
        return sum(self.stage_rays.values())

    def reuse_pass(self, stage: str, kernel, inputs: list, extra_outputs: tuple = (), in_place: bool = False,
                   parts: int | None = None) -> None:
        """A resampling pass of a method with reservoirs (`self.reservoirs`, a PingPong, and a
        scratch buffer `self.pass_out`): reads this sample's reservoirs, writes `pass_out`, then
        the two swap (ping-pong), so no pixel ever reads a reservoir another pixel of the pass
        wrote. A method whose history is read before its first pass (its first kernel resamples
        the new reservoirs with the history, fused) has no scratch buffer (`pass_out` None): the
        pass writes into the history's buffer, and the buffer it read becomes the history's.
        in_place: the race mutant, which writes the buffer it reads. parts: a pass made of that many
        launches, the part's index the kernel's first input (each launch reads the same input and
        carries its state on in the outputs, its per-pixel counts too: they are summed once, after
        the last)."""
        history_free = self.pass_out is None
        if history_free:
            self.pass_out = self.reservoirs.previous
        current = self.reservoirs.current
        out = current if in_place else self.pass_out
        if parts is None:
            self.run_stage(stage, kernel, [*inputs, current], [out, *extra_outputs])
        else:
            for j in range(parts):
                self.run_stage(stage, kernel, [j, *inputs, current], [out, *extra_outputs], new_call=j == 0,
                               tally=j == parts - 1)
        if not in_place:
            self.reservoirs.current, self.pass_out = self.pass_out, current
        if history_free:
            self.reservoirs.previous, self.pass_out = self.pass_out, None

    def stats(self) -> dict:
        """What the method reports about the frames rendered so far (the API adds wall times)."""
        self.collect_events()  # stages run outside a frame (tests, a component) count too
        stage_ms = sum(self.timer.ms.values())
        return {
            "device": str(self.device),
            "max_depth": self.settings.max_depth,
            "settings": self.settings.as_dict(),
            "stages": self.timer.summary(),
            "stage_total_ms": stage_ms,
            "rays": self.rays,
            "rays_by_stage": dict(self.stage_rays),
            "rays_per_second": self.rays / (stage_ms / 1e3) if stage_ms > 0 else 0.0,
            "bytes_per_pixel": self.buffers.per_pixel(self.num_pixels),
            "scene_bytes": self.dscene.memory_bytes(),
            "tracer": self.dscene.tracer_used,
            "counters": dict(self.counters),
            "notes": list(self.notes),
        }

    def allocate(self) -> None:
        raise NotImplementedError
