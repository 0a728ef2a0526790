"""Event tallies: per-pixel event arrays (events.py's packed `EventCounts`, and a pass's own
`PassCounts`, such as shift counts) summed on the device into named slots, and read by the host
once per frame.

A stage's events are summed right after its launch (the scratch array is rewritten by the next
stage), but only into a small device array: no stage waits for the host. Each thread of the sum
adds a chunk of pixels in int64 and then adds its chunk's totals atomically, so a GPU's atomics
meet in one address per chunk, not per pixel. A fifth sum counts the fields that saturated.
"""
from typing import Any

import numpy as np
import warp as wp

from .events import COUNT_BITS, COUNT_MAX, PASS_COUNT_MAX, EventCounts, PassCounts

CHUNK = wp.constant(256)
SUMS = 5  # four counts and the saturated fields


@wp.func
def unpacked(e: EventCounts) -> wp.vec4i:
    """A stage's counts in events.py's order: non-finite, zero-weight inputs, failed shifts, rays."""
    c = wp.vec4i(0, 0, 0, int(e[0]))
    for j in range(3):
        c[j] = int((e[1] >> wp.uint32(COUNT_BITS * j)) & wp.uint32(COUNT_MAX))
    return c


@wp.func
def saturated(e: EventCounts) -> int:
    c = unpacked(e)
    n = int(0)
    for j in range(3):  # the rays have 32 bits
        if c[j] == COUNT_MAX:
            n += 1
    return n


@wp.func
def unpacked(e: PassCounts) -> wp.vec4i:
    return wp.vec4i(int(e[0]), int(e[1]), int(e[2]), int(e[3]))


@wp.func
def saturated(e: PassCounts) -> int:
    n = int(0)
    for j in range(4):
        if int(e[j]) == PASS_COUNT_MAX:
            n += 1
    return n


@wp.kernel
def tally_kernel(counts: wp.array(dtype=Any), n: int, slot: int, sums: wp.array2d(dtype=wp.int64)):
    t = wp.tid()
    a = wp.vec4l()
    sat = wp.int64(0)
    for i in range(t * CHUNK, wp.min(t * CHUNK + CHUNK, n)):
        c = unpacked(counts[i])
        for j in range(4):
            a[j] += wp.int64(c[j])
        sat += wp.int64(saturated(counts[i]))
    for j in range(4):
        if a[j] != wp.int64(0):
            wp.atomic_add(sums, slot, j, a[j])
    if sat != wp.int64(0):
        wp.atomic_add(sums, slot, 4, sat)


TALLY_KERNELS = {t: wp.overload(tally_kernel, {"counts": wp.array(dtype=t)}) for t in (EventCounts, PassCounts)}


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
        wp.launch(TALLY_KERNELS[events.dtype], dim=(n + CHUNK - 1) // CHUNK, inputs=[events, n, slot, self.sums],
                  device=self.device)
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
