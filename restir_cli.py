"""The `restir` command's entry point, outside the package: a Ctrl-C while the package and Warp
import (up to a second or more on a cold start) ends as any other Ctrl-C does, with one line and
exit status 130, not a traceback. (`python -m restir` imports the package first and cannot.)

The Ctrl-C is also remembered, not only raised: a library that catches every exception while it
imports (a bare `except:` around an optional import) would swallow the KeyboardInterrupt, and the
command then went on to render (seen as a test that waited 120 s for a stop)."""
import signal
import sys

_interrupted = False


def _on_sigint(signum, frame):
    global _interrupted
    _interrupted = True
    raise KeyboardInterrupt


def main() -> int:
    previous = signal.signal(signal.SIGINT, _on_sigint)
    try:
        from restir.cli import main as run
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130
    finally:
        signal.signal(signal.SIGINT, previous)
    if _interrupted:  # raised during the import and swallowed there
        print("interrupted", file=sys.stderr)
        return 130
    return run()
