"""Name Warp's CPU kernels in `perf` profiles: render some frames of a method and, at exit, write
/tmp/perf-PID.map (the map file perf reads for JIT code) from the object file of every Warp module
the run loaded.

Warp compiles CPU modules in memory, so perf shows their code as `[JIT]` addresses. Each module
is an object file in the kernel cache with one code section; its load address is a kernel's
address (Warp's lookup) minus that kernel's offset in `nm`, and every function of the file
(kernels and the functions the compiler left out of line) gets its name from there. With
`--lines` the kernels are also built with line tables (the cc1 flag
`-debug-info-kind=line-tables-only`; Warp's build refuses `-g`), in their own cache, so that
`addr2line -i -e <object> -j .ltext <offset>` maps a sample to the generated C++, whose comments
name the Python line (`<L n>`). Only the timed frames are recorded (perf's control fifo).

    mkfifo /tmp/ctl; RESTIR_CPU_THREADS=1 taskset -c 0 perf record -o /tmp/p.data -F 999 -D -1 \\
        --control fifo:/tmp/ctl .venv/bin/python benchmarks/perf_symbols.py --method restir-pt \\
        --size 512 --frames 4 --ctl /tmp/ctl
    perf report -i /tmp/p.data --sort dso,sym --stdio

(How it was used: docs/changelog.md#speed-functions-that-copied-the-scene-inlined.)
"""
import argparse
import atexit
import os
import subprocess
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))


def record_loads():
    """Wrap Warp's CPU object loader; returns the list it fills with (object path, handle)."""
    import warp as wp

    wp.init()
    from warp._src import context

    llvm = context.runtime.llvm
    loads = []
    load = llvm.wp_load_obj

    def recorded(path, handle, legacy):
        status = load(path, handle, legacy)
        loads.append((path.decode(), handle.decode()))
        return status

    llvm.wp_load_obj = recorded
    return llvm, loads


def write_map(llvm, loads, path):
    lines = []
    for obj, handle in loads:
        syms = []
        for ln in subprocess.run(["nm", "-S", "--defined-only", obj], capture_output=True, text=True).stdout.splitlines():
            parts = ln.split()
            if len(parts) == 4 and parts[2] in "tT":
                syms.append((int(parts[0], 16), int(parts[1], 16), parts[3]))
        base = None
        for off, _, name in syms:
            if name.endswith("_cpu_forward"):
                addr = llvm.wp_lookup(handle.encode(), name.encode())
                if addr:
                    base = addr - off
                    break
        if base is not None:
            short = os.path.basename(obj)[:30]
            lines += [f"{base + off:x} {size:x} {short}:{name}" for off, size, name in syms]
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--method", default="restir-pt")
    ap.add_argument("--scene", default="cornell-box", help="a shared scene's name")
    ap.add_argument("--size", type=int, default=512)
    ap.add_argument("--frames", type=int, default=4)
    ap.add_argument("--max-depth", type=int, default=8)
    ap.add_argument("--lines", action="store_true", help="build with line tables (own cache: /tmp/warp_lines)")
    ap.add_argument("--ctl", help="perf's control fifo: recording is enabled for the timed frames only")
    args = ap.parse_args()
    if args.lines:
        os.environ["WARP_CACHE_PATH"] = "/tmp/warp_lines"
    llvm, loads = record_loads()
    atexit.register(write_map, llvm, loads, f"/tmp/perf-{os.getpid()}.map")
    import warp as wp

    import restir
    from tests.shared_scenes import scene_path

    if args.lines:
        wp.config.cpu_compiler_flags += " -debug-info-kind=line-tables-only"
    scene = restir.load_scene(str(scene_path(args.scene)))
    cfg = dict(method=args.method, width=args.size, height=args.size, spp=1, max_depth=args.max_depth)
    restir.render(scene, restir.RenderConfig(frames=2, **cfg))  # compile, warm up
    if args.ctl:
        open(args.ctl, "w").write("enable\n")
    t = time.time()
    r = restir.render(scene, restir.RenderConfig(frames=args.frames, **cfg))
    wall = time.time() - t
    if args.ctl:
        open(args.ctl, "w").write("disable\n")
    stages = {k: round(v["total_ms"] / args.frames) for k, v in r.stats["stages"].items() if v["total_ms"]}
    print(f"{args.method}: {wall / args.frames * 1e3:.0f} ms a frame (wall), stages {stages}")
    for obj, _ in loads:
        print("object:", obj)


if __name__ == "__main__":
    main()
