"""What every command shares: the argument parser's shape, option types, output checks made before
any work, the writers' error reporting, the console, the progress bar, scene loading with its
warnings, and the tev hand-off."""
import argparse
import json
import math
import os
import sys
import tempfile
import textwrap
import time
import warnings

from ..config import ConfigError
from ..scene.builtin import BUILTIN_DESCRIPTIONS
from ..scene.errors import SceneWarning
from ..scene.scene import MISSING_TEXTURES

# restir.validation.runs.DEFAULT_MAX_MDB as --max-mdb writes it (not imported: that pulls in scipy)
DEFAULT_MAX_MDB = "5%"
DEFAULT_TEV = "127.0.0.1:14158"


class Parser(argparse.ArgumentParser):
    """argparse with one-line errors (no usage block), status 2."""

    def error(self, message):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


class Formatter(argparse.ArgumentDefaultsHelpFormatter, argparse.RawDescriptionHelpFormatter):
    """Shows '(default: ...)' after each option's help, except where there is no default to show
    (None, off flags, empty lists) or the help already says it."""

    def _get_help_string(self, action):
        d = action.default
        if d is None or d is False or d == [] or "default" in (action.help or ""):
            return action.help
        return super()._get_help_string(action)


def add_command(sub, name: str, help: str):
    """A subcommand's parser with the shared formatter and the builtin scenes listed below its
    options."""
    return sub.add_parser(name, help=help, formatter_class=Formatter, epilog=builtins_epilog())


# ------------------------------------------------------------------ option types and groups
def key_value(text: str) -> tuple[str, str]:
    if "=" not in text:
        raise argparse.ArgumentTypeError(f"expected NAME=VALUE, got '{text}'")
    k, v = text.split("=", 1)
    return k.strip(), v.strip()


def path_argument(text: str) -> str:
    """argparse type of a file or folder argument: an empty one is refused (`-o ""` would
    otherwise mean the default path)."""
    if not text.strip():
        raise argparse.ArgumentTypeError("an empty path")
    return text


def finite_float(text: str) -> float:
    """argparse type: a float that is finite (nan and inf are refused, with the option's name)."""
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"invalid number: '{text}'") from None
    if not math.isfinite(v):
        raise argparse.ArgumentTypeError(f"must be a finite number, not '{text}'")
    return v


def fraction(text: str) -> float:
    """A bound on a relative bias: a fraction (0.05) or a percentage (5%)."""
    t = text.strip()
    try:
        v = float(t[:-1]) / 100 if t.endswith("%") else float(t)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a fraction such as 0.05 or a percentage such as 5%, got '{text}'") from None
    if not (v > 0 and math.isfinite(v)):
        raise argparse.ArgumentTypeError(f"must be above 0, got '{text}'")
    if not t.endswith("%") and v > 1:
        raise argparse.ArgumentTypeError(f"'{text}' as a fraction is over 100%; a percentage needs %, e.g. {t}%")
    return v


def builtins_epilog() -> str:
    lines = ["builtin scenes (SCENE = builtin:NAME):"]
    width = max(map(len, BUILTIN_DESCRIPTIONS)) + 2
    for name, text in BUILTIN_DESCRIPTIONS.items():
        lines += textwrap.wrap(text, 96, initial_indent=f"  {name:<{width}}", subsequent_indent=" " * (width + 2))
    return "\n".join(lines)


def scene_argument(p, help="Mitsuba 3 XML file, pbrt-v4 file (.pbrt), glTF 2.0 file (.gltf, .glb) or builtin:NAME (listed below)", **kw) -> None:
    p.add_argument("scene", help=help, **kw)


def defines_option(p) -> None:
    """The options that decide how the scene file is read: -D and --missing-textures."""
    p.add_argument("-D", dest="defines", action="append", type=key_value, default=[], metavar="NAME=VALUE",
                   help="override a scene <default> (as Mitsuba's -D)")
    p.add_argument("--missing-textures", choices=MISSING_TEXTURES, default="error",
                   help="a bitmap whose file is missing: stop (error, the default) or render it as constant "
                        "grey 0.5 with a warning (grey)")


def jitter_option(p) -> None:
    p.add_argument("--no-jitter", dest="jitter", action="store_false",
                   help="every primary ray through its pixel centre, for every method and the reference: a fixed "
                        "primary hit per pixel, the image the radiance at the centres (edges alias), as the Suffix "
                        "ReSTIR paper evaluates (default: samples spread by the film's filter, as in Mitsuba)")


def device_option(p) -> None:
    p.add_argument("--device", default="cpu", help="cpu or cuda (or cuda:N)")


def tev_option(p, what: str) -> None:
    p.add_argument("--tev", nargs="?", const=DEFAULT_TEV, metavar="HOST:PORT",
                   help=f"also send {what} to a running tev viewer (needs restir[tev]; default {DEFAULT_TEV})")


def fanout_options(p, what: str) -> None:
    p.add_argument("--workers", type=int, help=f"local processes rendering {what} (default: one per core)")
    p.add_argument("--ray", metavar="ADDRESS", help=f"render {what} on a Ray cluster: auto (the running one), an "
                   "address (ray://host:10001), or local (a private one on this machine); needs restir[ray]")


# ------------------------------------------------------------------ output paths, checked first
def _writable_folder(folder: str, what: str) -> None:
    """Create `folder` if missing (as the writers would) and make sure a file can be made there."""
    existing = folder
    while not os.path.exists(existing) and os.path.dirname(existing) != existing:
        existing = os.path.dirname(existing)
    if not os.path.isdir(existing):
        raise ConfigError(f"{what}: '{existing}' is not a folder")
    try:
        os.makedirs(folder, exist_ok=True)
    except OSError as e:
        missing = folder
        while not os.path.exists(os.path.dirname(missing)):
            missing = os.path.dirname(missing)
        raise ConfigError(f"{what}: cannot create folder '{missing}': {e.strerror}") from None
    try:
        fd, probe = tempfile.mkstemp(dir=folder, prefix=".restir-write-test-")
        os.close(fd)
        os.remove(probe)
    except OSError as e:
        raise ConfigError(f"{what}: cannot write in folder '{folder}': {e.strerror}") from None


def check_output(path: str, option: str, formats=None) -> None:
    """Refuse now, before the render, an output file that could not be written after it: a
    folder, an extension not in `formats` (when given), a folder that cannot be created or
    written, a file that cannot be overwritten."""
    what = f"{option} {path}"
    if path.endswith(("/", os.sep)) or os.path.isdir(path):
        raise ConfigError(f"{what}: is a folder; give a file name")
    if formats is not None:
        ext = os.path.splitext(path)[1].lower()
        if ext not in formats:
            why = f"unsupported extension '{ext}'" if ext else "no extension to choose the format by"
            raise ConfigError(f"{what}: {why} (use {', '.join(formats)})")
    _writable_folder(os.path.dirname(os.path.abspath(path)), what)
    if os.path.exists(path) and not os.access(path, os.W_OK):
        raise ConfigError(f"{what}: the file exists and cannot be overwritten")


def check_output_folder(path: str, option: str) -> None:
    what = f"{option} {path}"
    if os.path.exists(path) and not os.path.isdir(path):
        raise ConfigError(f"{what}: not a folder")
    _writable_folder(os.path.abspath(path), what)


def write(path: str, writer, *args) -> None:
    try:
        writer(path, *args)
    except OSError as e:  # after the checks: a full disk, a folder removed meanwhile, ...
        raise ConfigError(f"cannot write {path}: {e.strerror or e}") from None


def write_json(path: str, data: dict) -> None:
    with open(path, "w") as f:
        json.dump(data, f, indent=2, default=str)


# ------------------------------------------------------------------ console, progress, scene, tev
def console(quiet: bool = False):
    """The console of notes, warnings and progress: stderr, silent with --quiet (load_scene says
    the scene's warnings all the same)."""
    from rich.console import Console

    return Console(stderr=True, quiet=quiet)


def results_console():
    """The console of result tables: stdout, 200 columns when not a terminal (logs, pipes)."""
    from rich.console import Console

    return Console(width=None if sys.stdout.isatty() else 200)


def say(con, text: str, prefix: str = "") -> None:
    """One line of plain text (no markup read in it, no highlighting), wrapped only by the
    terminal."""
    from rich.markup import escape

    con.print(prefix + escape(text), highlight=False, soft_wrap=True)


def progress_bar(con, *columns):
    """A transient bar: the task's description, the bar, `columns` (counts, percentages), the
    elapsed time."""
    from rich.progress import BarColumn, Progress, TimeElapsedColumn

    return Progress("[progress.description]{task.description}", BarColumn(), *columns, TimeElapsedColumn(),
                    console=con, transient=True)


class _LoadProgress:
    """A bar for a scene load that is slow: shown only once the load has taken SHOW_AFTER seconds,
    so a small scene prints nothing."""

    SHOW_AFTER = 1.0

    def __init__(self, con, spec: str):
        self.con, self.spec = con, spec
        self.start = time.perf_counter()
        self.bar = self.task = None

    def __call__(self, done: int, total: int) -> None:
        if self.bar is None:
            if time.perf_counter() - self.start < self.SHOW_AFTER:
                return
            from rich.progress import MofNCompleteColumn

            self.bar = progress_bar(self.con, MofNCompleteColumn())
            self.bar.start()
            self.task = self.bar.add_task(f"loading {os.path.basename(self.spec)} (scene elements)", total=total)
        self.bar.update(self.task, completed=done, total=total)

    def close(self) -> float:
        """Stop the bar; the load's seconds."""
        if self.bar is not None:
            self.bar.stop()
        return time.perf_counter() - self.start


def load_scene(spec: str, defines, con, missing_textures: str = "error"):
    """api.load_scene with each SceneWarning said on `con` (one line each), a progress bar when
    the load takes over a second, and its time said then."""
    from .. import api

    shown = _LoadProgress(con, spec)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", SceneWarning)
        try:
            scene = api.load_scene(spec, dict(defines) or None, missing_textures=missing_textures, progress=shown)
        finally:
            seconds = shown.close()
    if seconds > _LoadProgress.SHOW_AFTER:
        say(con, f"loaded {spec} in {seconds:.1f} s ({scene.num_triangles:,} triangles)")
    for w in caught:
        if issubclass(w.category, SceneWarning):  # said even with --quiet: a warning is not a note
            say(console() if con.quiet else con, str(w.message), "[yellow]warning:[/] ")
        else:
            warnings.showwarning(w.message, w.category, w.filename, w.lineno)
    return scene


def open_tev(address):
    """The tev connection of --tev ADDRESS, made before any render (a missing package or viewer is
    said now), or None without --tev."""
    if not address:
        return None
    from ..tev import connect_tev

    return connect_tev(address)


def close_tev(tev) -> None:
    if tev is not None:
        tev.__exit__(None, None, None)
