"""The one launch helper every stage uses.

Warp runs a CPU launch serially on one thread, but releases the Python lock while a CPU kernel
runs. So on the CPU a pixel launch is split into disjoint index ranges ("slices"), launched from
a thread pool; every pixel kernel takes `offset` as its first argument and handles pixel
wp.tid() + offset. Pixels never read each other's outputs within a launch (ping-pong), and the
random numbers are counter-based, so the result is bitwise independent of the slicing.
On CUDA the launch is one grid.

Consequence: Warp's atomics are not atomic between CPU slices (Warp assumes one host thread
per launch), so a kernel launched here must not accumulate into shared memory with atomics;
it writes per-item outputs that are reduced afterwards. Nor may it use Warp's tiles: Warp 1.19
keeps a CPU launch's tile memory through one pointer per module, shared by the slices' threads
(which is also why the debug-mode test run turns `enable_tiles_in_stack_memory` off).
"""
import os
from concurrent.futures import ThreadPoolExecutor

import warp as wp

_pool: ThreadPoolExecutor | None = None
_pool_size = 0


def default_slices() -> int:
    env = os.environ.get("RESTIR_CPU_THREADS")
    return max(1, int(env)) if env else max(1, os.cpu_count() or 1)


def _executor(n: int) -> ThreadPoolExecutor:
    global _pool, _pool_size
    if _pool is None or _pool_size < n:
        if _pool is not None:
            _pool.shutdown(wait=True)
        _pool, _pool_size = ThreadPoolExecutor(max_workers=n, thread_name_prefix="restir-cpu"), n
    return _pool


def launch_pixels(kernel, count: int, inputs: list, outputs: list, device, slices: int | None = None,
                  reverse: bool = False) -> None:
    """Launch `kernel(offset, *inputs, *outputs)` over `count` items, split over CPU cores.

    reverse (a debug permutation, docs/validation.md#level-7-races-and-determinism): run the slices
    one after another, last first,
    so that items are processed in a different order than any forward launch; a correct pass gives
    bitwise the same result, a pass that reads its own outputs does not.
    """
    device = wp.get_device(device)
    if count <= 0:
        return
    if reverse and device.is_cpu:
        n = min(slices or default_slices(), count)
        bounds = [count * i // n for i in range(n + 1)]
        for i in reversed(range(n)):
            wp.launch(kernel, dim=bounds[i + 1] - bounds[i], inputs=[bounds[i], *inputs], outputs=outputs, device=device)
        return
    if device.is_cuda:
        wp.launch(kernel, dim=count, inputs=[0, *inputs], outputs=outputs, device=device)
        return
    n = min(slices or default_slices(), count)
    if n == 1:
        wp.launch(kernel, dim=count, inputs=[0, *inputs], outputs=outputs, device=device)
        return
    # Load (compile) once on this thread; concurrent first loads would race on the cache.
    wp.load_module(kernel.module, device=device)
    bounds = [count * i // n for i in range(n + 1)]

    def run(i):
        wp.launch(kernel, dim=bounds[i + 1] - bounds[i], inputs=[bounds[i], *inputs], outputs=outputs, device=device)

    list(_executor(n).map(run, range(n)))
