"""User-facing scene errors and warnings, always naming the file and line."""
import warnings


class SceneError(Exception):
    """A scene that cannot be rendered correctly. `loc` is 'file:line' (or a builtin's name)."""

    def __init__(self, message: str, loc: str | None = None):
        self.loc = loc
        self.message = message
        super().__init__(f"{loc}: {message}" if loc else message)


class SceneWarning(UserWarning):
    """Something the loader ignored (usually a typo in a parameter name)."""


def warn(message: str, loc: str | None = None) -> None:
    warnings.warn(f"{loc}: {message}" if loc else message, SceneWarning, stacklevel=3)
