"""Command line: `restir COMMAND ...` (the contract in docs/reference/cli.md), one module per
command (render, validate, compare, sweep, info, view: each `add_parser(sub)` and `run(args)`) and
common.py for what they share.

Arguments are parsed into the API's configs; user errors print one line (`file:line: error:
...`, or `restir render: error: ...` for a bad argument) and exit with status 2, never a
traceback. Output paths are checked before any work is done.
"""
import sys
import warnings

from ..config import ConfigError
from ..scene.errors import SceneError
from . import compare, info, render, sweep, validate, view
from .common import DEFAULT_MAX_MDB, Parser, fraction

COMMANDS = {"render": render, "info": info, "validate": validate, "compare": compare, "sweep": sweep, "view": view}
__all__ = ["main", "build_parser", "COMMANDS", "DEFAULT_MAX_MDB", "fraction"]


def build_parser() -> Parser:
    from .. import __version__

    ap = Parser(prog="restir", description="Research renderer for resampled path tracing.")
    ap.add_argument("--version", action="version", version=f"restir {__version__}")
    sub = ap.add_subparsers(dest="command", required=True)
    for command in COMMANDS.values():
        command.add_parser(sub)
    return ap


def main(argv=None) -> int:
    try:
        args = build_parser().parse_args(argv)
    except SystemExit as e:  # --help, --version (0) and one-line argument errors (2)
        return e.code if isinstance(e.code, int) else 0 if e.code is None else 2
    try:
        # numpy's and scipy's RuntimeWarnings (a division by a zero variance, say) are for
        # developers: they printed a source line of a library; what a user needs is in the results
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            return COMMANDS[args.command].run(args)
    except (SceneError, ConfigError) as e:
        msg = e.message if isinstance(e, SceneError) else str(e)
        # a scene's error names its file and line; any other is the command's
        where = f"{e.loc}: " if isinstance(e, SceneError) and e.loc else f"restir {args.command}: "
        print(f"{where}error: {msg}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130
