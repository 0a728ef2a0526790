"""Typed method settings: a dataclass per method, one field per setting with its `--set` key, its
default, its one-line meaning (`restir info`) and whether it is static (it selects which kernels
are built: a change compiles other code) or runtime (a value the kernels read).

    @dataclasses.dataclass
    class MySettings(Settings):
        candidates: int = setting("candidates", 4, "light candidates per pixel")
        mutation: str = setting("debug.mutation", "none", "fault injection (biased)", static=True)

A method names its class (`Integrator.Settings`); the integrator reads `self.settings.candidates`.
Every settings object also holds the render's own settings (seed, spp, max_depth, camera motion,
the scene's Russian-roulette depth and hide_emitters), filled by the API from the RenderConfig
and the scene, never by `--set`; and the `--set` settings every method has, `emission.rays` and `emission.adaptive`. A
component's settings nest under a prefix (`di.*`: `component(...)`), so `--set di.candidates=8`
reaches `settings.di.candidates`.
"""
import dataclasses
import functools

from .config import ConfigError, parse_value

MAX_EMISSION_RAYS = 64  # emission.rays: camera rays per sample for the emission seen directly
EMISSION_RAYS_DOC = ("camera rays per pixel sample that estimate the emission seen directly (the sample's own "
                     "and n - 1 more spread over the pixel); the rest of the path starts at the sample's own hit")
EMISSION_ADAPTIVE_DOC = ("with emission.rays > 1: trace the extra rays only at pixels where one of the last 16 "
                         "launches saw the emission vary in the 3x3 neighbourhood (an emitter's edge) or near an "
                         "emitter at most 2 px wide on screen, one ray elsewhere (unbiased: decided from earlier, "
                         "independent samples and the geometry)")
MUTATION_DOC = "fault injection for the mutation tests (biased; the harness refuses it)"  # debug.mutation


def setting(key: str, default, doc: str, *, static: bool = False):
    """A method setting: its `--set` key, default, one-line meaning, and static (selects kernels)
    or runtime (a kernel parameter)."""
    return dataclasses.field(default=default, metadata={"key": key, "doc": doc, "static": static})


def component(prefix: str, factory, doc_prefix: str = "", exclude: tuple = (), doc_args: dict | None = None):
    """A component's settings (a SettingsGroup dataclass made by `factory`) under `prefix` ("di."),
    its keys' meanings prefixed by `doc_prefix` (and formatted with `doc_args` where given: the
    "{radius_at_1080}" of the spatial-reuse settings), without the keys in `exclude`."""
    return dataclasses.field(default_factory=factory, metadata={"prefix": prefix, "doc_prefix": doc_prefix,
                                                                "exclude": exclude, "doc_args": doc_args})


@dataclasses.dataclass
class SettingsGroup:
    """A group of `--set` settings: the key table and reading or writing a setting by its key.
    A method's settings are a `Settings`; a part shared by methods (the spatial-reuse settings)
    is a group nested with `component`."""

    # ------------------------------------------------------------------ the table of keys
    @classmethod
    @functools.cache  # per class: read on every sample by code generic over methods (`get`)
    def entries(cls) -> tuple:
        """(key, path of attribute names, default, doc, static) of every `--set` setting, a
        component's under its prefix."""
        out = []
        for f in dataclasses.fields(cls):
            if "key" in f.metadata:
                out.append((f.metadata["key"], (f.name,), f.default, f.metadata["doc"], f.metadata["static"]))
            elif "prefix" in f.metadata:
                inner = f.default_factory()
                args = f.metadata["doc_args"]
                for key, path, _, doc, static in type(inner).entries():
                    if key not in f.metadata["exclude"]:
                        default = _get(inner, path)
                        out.append((f.metadata["prefix"] + key, (f.name, *path), default,
                                    f.metadata["doc_prefix"] + (doc.format(**args) if args else doc), static))
        return tuple(out)

    @classmethod
    def defaults(cls) -> dict:
        """{key: default} (what `restir info` lists)."""
        return {key: default for key, _, default, _, _ in cls.entries()}

    @classmethod
    def docs(cls) -> dict:
        return {key: doc for key, _, _, doc, _ in cls.entries()}

    @classmethod
    def static_keys(cls) -> tuple:
        return tuple(key for key, _, _, _, static in cls.entries() if static)

    def get(self, key: str):
        """A setting by its key (for code generic over methods)."""
        return _get(self, self._path(key))

    def set(self, key: str, value) -> None:
        _set(self, self._path(key), value)

    @classmethod
    def _path(cls, key: str) -> tuple:
        path = next((path for k, path, _, _, _ in cls.entries() if k == key), None)
        if path is None:
            raise KeyError(key)
        return path


@dataclasses.dataclass
class Settings(SettingsGroup):
    """A method's settings: its `--set` groups and the render's settings every method has (from
    the RenderConfig and the scene; not `--set`)."""
    seed: int = 0
    spp: int = 1
    max_depth: int = 5
    camera_motion: str = "none"
    camera_speed: float = 1.0
    rr_depth: int = 5
    hide_emitters: bool = False
    # a --set setting every method has: where the primary rays are traced (common/primary_hits.py)
    emission_rays: int = setting("emission.rays", 1, EMISSION_RAYS_DOC)
    emission_adaptive: bool = setting("emission.adaptive", True, EMISSION_ADAPTIVE_DOC)

    # ------------------------------------------------------------------ building and reading
    @classmethod
    def from_overrides(cls, overrides: dict, **render):
        """The defaults with `overrides` ({key: value}; strings parsed by the default's type) and
        the render's settings; an unknown key or a bad value is a ConfigError."""
        paths = {key: (path, default) for key, path, default, _, _ in cls.entries()}
        out = cls(**render)
        for key, value in overrides.items():
            if key not in paths:
                raise ConfigError(f"unknown setting '{key}' (known: {', '.join(sorted(paths)) or 'none'})")
            path, default = paths[key]
            _set(out, path, parse_value(value, default) if isinstance(value, str) else value)
        return out

    def check_common(self) -> None:
        """The --set settings every method has, refused before anything is built."""
        if not 1 <= self.emission_rays <= MAX_EMISSION_RAYS:
            raise ConfigError(f"emission.rays must be in [1, {MAX_EMISSION_RAYS}]")

    def as_dict(self) -> dict:
        """{key: value} of every `--set` setting, then the render's (the stats' "settings")."""
        return {**{key: _get(self, path) for key, path, _, _, _ in self.entries()}, **self.render_settings()}

    def render_settings(self) -> dict:
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(Settings) if "key" not in f.metadata}


def _get(obj, path):
    for name in path:
        obj = getattr(obj, name)
    return obj


def _set(obj, path, value) -> None:
    for name in path[:-1]:
        obj = getattr(obj, name)
    setattr(obj, path[-1], value)
