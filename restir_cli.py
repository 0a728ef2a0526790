"""The `restir` command's entry point, outside the package: a Ctrl-C while the package and Warp
import (up to a second or more on a cold start) ends as any other Ctrl-C does, with one line and
exit status 130, not a traceback. (`python -m restir` imports the package first and cannot.)"""
import sys


def main() -> int:
    try:
        from restir.cli import main as run
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130
    return run()
