"""`restir view` (docs/guide/view.md): live.py renders frames from a given camera without a
browser, controls.py makes the controls from the methods' typed settings, camera.py converts
between the browser's camera and restir's, and server.py is the web server (viser) around them.
`view` is the Python API's entry, `restir.view`."""
import math

from ..config import ConfigError


def view(scene, method: str = "restir-pt", settings: dict | None = None, device: str = "cpu", spp: int = 1,
         max_depth: int | None = None, height: int | None = None, exposure: float = 0.0, reference=None,
         output_dir: str = ".", host: str = "127.0.0.1", port: int = 8080, on_ready=None, on_compile=None) -> None:
    """Open the interactive viewer: a local web server that renders `scene` with `method` from the
    camera the browser sends, until Ctrl-C (a KeyboardInterrupt, raised after the server is shut
    down). Bad settings are refused (ConfigError) before the server starts. `on_ready(url)` is
    called once it listens (default: the URL is printed)."""
    from .. import limits
    from .live import LiveRender
    from .server import Viewer

    problem = limits.side_problem("height", height) if height is not None else None
    if problem or not math.isfinite(exposure):
        raise ConfigError(problem or "exposure must be a finite number")
    live = LiveRender(scene, method, settings, device, spp, max_depth, on_compile=on_compile)
    viewer = Viewer(live, host, port, height, exposure, reference, output_dir)
    (on_ready or print)(viewer.url)
    viewer.run()
