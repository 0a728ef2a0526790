"""`restir info`: the methods with their settings (defaults, meanings) and the builtin scenes."""
from .common import builtins_epilog


def add_parser(sub) -> None:
    sub.add_parser("info", help="list the methods with their settings (defaults, meanings) and the builtin scenes")


def run(args) -> int:
    from .. import __version__
    from ..integrators import METHODS

    print(f"restir {__version__}\n\nmethods (--method NAME; settings with --set KEY=VALUE):")
    for name, cls in METHODS.items():
        print(f"  {name}: {cls.DESCRIPTION}")
        for key, default in cls.SETTINGS.items():
            value = str(default).lower() if isinstance(default, bool) else default
            print(f"    {key + '=' + str(value):<28} {cls.SETTINGS_DOC[key]}")
    print()
    print(builtins_epilog())
    return 0
