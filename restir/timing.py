"""Per-stage wall-clock timing (synchronized) and a registry of buffer sizes for memory stats."""
import time
from collections import defaultdict
from contextlib import contextmanager

import warp as wp


class StageTimer:
    def __init__(self, device):
        self.device = device
        self.ms: dict[str, float] = defaultdict(float)
        self.calls: dict[str, int] = defaultdict(int)

    @contextmanager
    def stage(self, name: str, new_call: bool = True):
        """Time one run of a stage (new_call=False: one more part of the run just timed)."""
        wp.synchronize_device(self.device)
        t0 = time.perf_counter()
        yield
        wp.synchronize_device(self.device)
        self.ms[name] += (time.perf_counter() - t0) * 1e3
        self.calls[name] += int(new_call)

    def summary(self) -> dict:
        return {k: {"total_ms": v, "calls": self.calls[k], "ms_per_call": v / max(1, self.calls[k])} for k, v in self.ms.items()}


class BufferRegistry:
    """Named device buffers with their byte sizes; bytes per pixel are reported per buffer."""

    def __init__(self):
        self.bytes: dict[str, int] = {}

    def add(self, name: str, array) -> None:
        self.bytes[name] = int(array.capacity)

    def per_pixel(self, pixels: int) -> dict:
        out = {k: v / pixels for k, v in self.bytes.items()}
        out["total"] = sum(self.bytes.values()) / pixels
        return out
