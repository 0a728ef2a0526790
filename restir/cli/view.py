"""`restir view SCENE`: the scene in the browser, rendered continuously by one method from the
camera the browser sends (restir/viewer/). Prints the URL; Ctrl-C stops the server (exit 130)."""
import sys

from ..config import ConfigError
from .common import (add_command, check_output_folder, console, defines_option, device_option, finite_float,
                     key_value, load_scene, path_argument, say, scene_argument)


def add_parser(sub) -> None:
    v = add_command(sub, "view", "fly through a scene in the browser, watching a method render it")
    scene_argument(v)
    v.add_argument("--method", default="restir-pt", help="pt, restir-di, restir-pt or suffix-restir (switchable in "
                   "the page; default restir-pt)")
    v.add_argument("--set", dest="settings", action="append", type=key_value, default=[], metavar="KEY=VALUE",
                   help="a method setting (`restir info` lists them), as in restir render")
    v.add_argument("--spp", type=int, default=1, help="samples per pixel per frame (default 1)")
    v.add_argument("--max-depth", type=int, help="Mitsuba's max_depth (default: the scene's)")
    v.add_argument("--height", type=int, help="film height while the camera is still (default: the scene's; the "
                   "width follows the browser window)")
    v.add_argument("--exposure", type=finite_float, default=0.0, help="exposure in stops")
    v.add_argument("--reference", metavar="FILE.exr", type=path_argument,
                   help="an image of the scene's own camera and size, for the error view")
    v.add_argument("--output-dir", metavar="DIR", type=path_argument, default=".",
                   help="where 'save frame' writes its EXR, PNG and camera (default: the current folder)")
    v.add_argument("--host", default="127.0.0.1", help="address to listen on (default 127.0.0.1: this machine "
                   "only; reach a remote one through an SSH port forward)")
    v.add_argument("--port", type=int, default=8080, help="port (default 8080; the next free one if taken)")
    device_option(v)
    defines_option(v)


def run(args) -> int:
    from ..viewer import view

    con = console(False)
    if not 1 <= args.port <= 65535:
        raise ConfigError(f"--port {args.port}: not a port (1-65535)")
    check_output_folder(args.output_dir, "--output-dir")
    reference = None
    if args.reference:
        from ..image_io import read_exr

        try:
            reference = read_exr(args.reference)
        except Exception as e:  # noqa: BLE001  (any unreadable file: one line, before the server starts)
            raise ConfigError(f"--reference {args.reference}: not a readable EXR ({e})") from None
    if args.host not in ("127.0.0.1", "localhost", "::1"):
        say(con, f"listening on {args.host}: anyone who can reach this address can use the viewer", "warning: ")
    scene = load_scene(args.scene, args.defines, con, args.missing_textures)
    try:
        view(scene, method=args.method, settings=dict(args.settings), device=args.device, spp=args.spp,
             max_depth=args.max_depth, height=args.height, exposure=args.exposure, reference=reference,
             output_dir=args.output_dir, host=args.host, port=args.port,
             on_ready=lambda url: con.print(f"restir view: open {url} in a browser (Ctrl-C stops)"),
             on_compile=lambda: con.print("compiling kernels (once per configuration)..."))
    except KeyboardInterrupt:
        print("restir view: stopped", file=sys.stderr)
        return 130
    return 0
