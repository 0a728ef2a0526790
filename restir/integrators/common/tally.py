"""Event tallies: per-pixel vec4i event arrays (events.py, and a method's own, such as shift
counts) summed on the device into named slots, and read by the host once per frame.

A stage's events are summed right after its launch (the scratch array is rewritten by the next
stage), but only into a small device array: no stage waits for the host. Each thread of the sum
adds a chunk of pixels in int64 and then adds its chunk's totals atomically, so a GPU's atomics
meet in one address per chunk, not per pixel.
"""
import warp as wp

CHUNK = wp.constant(256)


@wp.kernel
def tally_kernel(events: wp.array(dtype=wp.vec4i), n: int, slot: int, sums: wp.array2d(dtype=wp.int64)):
    t = wp.tid()
    begin = t * CHUNK
    end = wp.min(begin + CHUNK, n)
    a = wp.int64(0)
    b = wp.int64(0)
    c = wp.int64(0)
    d = wp.int64(0)
    for i in range(begin, end):
        e = events[i]
        a += wp.int64(e[0])
        b += wp.int64(e[1])
        c += wp.int64(e[2])
        d += wp.int64(e[3])
    if a != wp.int64(0):
        wp.atomic_add(sums, slot, 0, a)
    if b != wp.int64(0):
        wp.atomic_add(sums, slot, 1, b)
    if c != wp.int64(0):
        wp.atomic_add(sums, slot, 2, c)
    if d != wp.int64(0):
        wp.atomic_add(sums, slot, 3, d)


class EventTally:
    """Sums of vec4i event arrays by key (any hashable: a stage, a pass), kept on the device
    until `read`."""

    CAPACITY = 256  # distinct keys of one integrator (a method and its components share one tally)

    def __init__(self, device):
        self.device = device
        self.sums = wp.zeros((self.CAPACITY, 4), dtype=wp.int64, device=device)
        self.slots: dict = {}
        self.pending = False

    def add(self, key, events: wp.array, n: int | None = None) -> None:
        """Add the first n (default: all) entries of `events` to `key`'s sum, on the device."""
        slot = self.slots.setdefault(key, len(self.slots))
        if slot >= self.CAPACITY:
            raise RuntimeError(f"more than {self.CAPACITY} event keys in one integrator")
        n = events.shape[0] if n is None else n
        wp.launch(tally_kernel, dim=(n + CHUNK - 1) // CHUNK, inputs=[events, n, slot, self.sums],
                  device=self.device)
        self.pending = True

    def read(self) -> dict:
        """{key: its four sums (int64)} since the last read, for every key ever added (one copy to
        the host); then zero."""
        if not self.pending:
            return {}
        sums = self.sums.numpy()
        out = {key: sums[slot].copy() for key, slot in self.slots.items()}
        self.sums.zero_()
        self.pending = False
        return out
