"""Event tallies: per-pixel event arrays (events.py's packed `EventCounts`, and a pass's own
`PassCounts`, such as shift counts) summed on the device into named slots, and read by the host
once per frame.

A stage's events are summed right after its launch (the scratch array is rewritten by the next
stage), but only into a small device array: no stage waits for the host. Each thread of the sum
adds a chunk of pixels in int64 and then adds its chunk's totals atomically, so a GPU's atomics
meet in one address per chunk, not per pixel. A fifth sum counts the fields that saturated.
"""
import numpy as np
import warp as wp

from .events import COUNT_BITS, COUNT_MAX, PASS_COUNT_MAX, EventCounts, PassCounts

CHUNK = wp.constant(256)
SUMS = 5  # four counts and the saturated fields


@wp.func
def add_chunk(sums: wp.array2d(dtype=wp.int64), slot: int, a: wp.vec4l, saturated: wp.int64):
    for j in range(4):
        if a[j] != wp.int64(0):
            wp.atomic_add(sums, slot, j, a[j])
    if saturated != wp.int64(0):
        wp.atomic_add(sums, slot, 4, saturated)


@wp.kernel
def tally_events_kernel(events: wp.array(dtype=EventCounts), n: int, slot: int, sums: wp.array2d(dtype=wp.int64)):
    """Sums in events.py's order: non-finite, zero-weight inputs, failed shifts, rays."""
    t = wp.tid()
    a = wp.vec4l()
    saturated = wp.int64(0)
    for i in range(t * CHUNK, wp.min(t * CHUNK + CHUNK, n)):
        e = events[i]
        for j in range(3):
            c = int((e[1] >> wp.uint32(COUNT_BITS * j)) & wp.uint32(COUNT_MAX))
            a[j] += wp.int64(c)
            if c == COUNT_MAX:
                saturated += wp.int64(1)
        a[3] += wp.int64(e[0])
    add_chunk(sums, slot, a, saturated)


@wp.kernel
def tally_counts_kernel(counts: wp.array(dtype=PassCounts), n: int, slot: int, sums: wp.array2d(dtype=wp.int64)):
    t = wp.tid()
    a = wp.vec4l()
    saturated = wp.int64(0)
    for i in range(t * CHUNK, wp.min(t * CHUNK + CHUNK, n)):
        e = counts[i]
        for j in range(4):
            c = int(e[j])
            a[j] += wp.int64(c)
            if c == PASS_COUNT_MAX:
                saturated += wp.int64(1)
    add_chunk(sums, slot, a, saturated)


class EventTally:
    """Sums of per-pixel count arrays by key (any hashable: a stage, a pass), kept on the device
    until `read`."""

    CAPACITY = 256  # distinct keys of one integrator (a method and its components share one tally)

    def __init__(self, device):
        self.device = device
        self.sums = wp.zeros((self.CAPACITY, SUMS), dtype=wp.int64, device=device)
        self.slots: dict = {}
        self.pending = False

    def add(self, key, events: wp.array, n: int | None = None) -> None:
        """Add the first n (default: all) entries of `events` (EventCounts or PassCounts) to
        `key`'s sums, on the device."""
        slot = self.slots.setdefault(key, len(self.slots))
        if slot >= self.CAPACITY:
            raise RuntimeError(f"more than {self.CAPACITY} event keys in one integrator")
        n = events.shape[0] if n is None else n
        kernel = tally_events_kernel if events.dtype == EventCounts else tally_counts_kernel
        wp.launch(kernel, dim=(n + CHUNK - 1) // CHUNK, inputs=[events, n, slot, self.sums], device=self.device)
        self.pending = True

    def read(self) -> dict:
        """{key: its five sums (int64): the four counts, then how many fields saturated} since the
        last read, for every key ever added (one copy to the host); then zero."""
        if not self.pending:
            return {}
        sums = self.sums.numpy()
        out = {key: np.array(sums[slot]) for key, slot in self.slots.items()}
        self.sums.zero_()
        self.pending = False
        return out
