"""Independent renders fanned out: in this process, on a local process pool, or on a Ray cluster.

A task is `render_task(scene, config)`: one render of a loaded scene (scenes and configs pickle,
so they travel to pool workers and through Ray's object store), returning its RenderResult.
Renders are deterministic functions of (scene, config) on the CPU, so the same seeds give
bitwise the same images wherever they run. Each worker process loads the kernels from Warp's
kernel cache on its node's disk (`WARP_CACHE_PATH`, default ~/.cache/warp). Before a local pool
starts, this process compiles every distinct configuration once (a 16x16 frame), so the workers
only load. On Ray, the first tasks of a configuration on a node compile it; Warp builds each
compilation in a folder of its own and renames it into the cache, so tasks that start together
compile it side by side harmlessly and every later task on that node loads it.
"""
import concurrent.futures as cf
import multiprocessing as mp
import os

from .config import ConfigError


def render_task(scene, config):
    """One render; the unit of work of every fan-out (top level, so that it pickles)."""
    from .api import render

    return render(scene, config)


def warm_kernels(tasks) -> None:
    """Compile (or load) the kernels of every distinct configuration in `tasks` here, on a 16x16
    frame, so that pool workers find them in the kernel cache."""
    import dataclasses

    from .api import make_integrator, sized_scene

    seen = set()
    for scene, config in tasks:
        key = (id(scene), config.method, repr(sorted(config.settings.items())), config.max_depth, config.device,
               config.tracer)
        if key in seen:
            continue
        seen.add(key)
        small = dataclasses.replace(config, width=16, height=16, frames=1, spp=1, aovs=())
        make_integrator(sized_scene(scene, small), small).render_frame(0)


def default_workers() -> int:
    return max(1, os.cpu_count() or 1)


def last_frame_task(scene, config):
    """One render's last frame alone (H, W, 3): what the error-structure runs of `compare` need,
    without sending every frame back."""
    import dataclasses

    from .api import render

    return render(scene, dataclasses.replace(config, keep_frames=True)).frame_images[-1]


def run_tasks(tasks, workers: int | None = None, ray: str | None = None, progress=None, task=render_task) -> list:
    """Run `task(scene, config)` (a top-level function, so that it pickles; default
    `render_task`) for each (scene, config) in `tasks`; results in task order.

    ray: None for local execution; "auto" (or an address such as "ray://head:10001") to join a
    running Ray cluster; "local" to start a private one on this machine. workers: local processes
    (default: one per core; 1 runs in this process). progress(done, total) after each task.
    """
    tasks = list(tasks)
    if ray is not None:
        return _run_on_ray(tasks, ray, progress, task)
    workers = workers or default_workers()
    if workers < 1:
        raise ConfigError("--workers must be >= 1")
    results = [None] * len(tasks)
    if workers == 1 or len(tasks) <= 1:
        for i, (scene, config) in enumerate(tasks):
            results[i] = task(scene, config)
            if progress:
                progress(i + 1, len(tasks))
        return results
    warm_kernels(tasks)
    # spawn, not fork: Warp and Embree hold native state that a forked child must not share
    with cf.ProcessPoolExecutor(max_workers=min(workers, len(tasks)), mp_context=mp.get_context("spawn")) as pool:
        futures = {pool.submit(task, scene, config): i for i, (scene, config) in enumerate(tasks)}
        for done, fut in enumerate(cf.as_completed(futures), start=1):
            results[futures[fut]] = fut.result()
            if progress:
                progress(done, len(tasks))
    return results


def _run_on_ray(tasks, address: str, progress, task=render_task) -> list:
    try:
        import ray
    except ImportError:
        raise ConfigError("--ray needs Ray: pip install 'restir[ray]'") from None
    if not ray.is_initialized():
        if address == "local":
            ray.init(include_dashboard=False, log_to_driver=False)
        else:
            ray.init(address=address, include_dashboard=False, log_to_driver=False)
    remote = ray.remote(num_cpus=1)(task)
    refs = [remote.remote(scene, config) for scene, config in tasks]
    index = {r: i for i, r in enumerate(refs)}
    results = [None] * len(refs)
    pending, done = list(refs), 0
    while pending:
        ready, pending = ray.wait(pending, num_returns=1)
        for r in ready:
            results[index[r]] = ray.get(r)
            done += 1
            if progress:
                progress(done, len(refs))
    return results
