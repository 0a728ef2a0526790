"""Typed access to one object's parameters; parameters never read become warnings (typos)."""
import math

import numpy as np

from .errors import SceneError, warn

_META = {"type", "_loc", "_kind", "id", "_ids", "_base_dir", "_animation"}


class Props:
    def __init__(self, obj: dict, ids: dict | None = None):
        self.obj = obj
        self.ids = ids or {}
        self.loc = obj.get("_loc", "<dict>")
        self.queried: set[str] = set()

    @property
    def type(self) -> str:
        return self.obj["type"]

    def has(self, name: str) -> bool:
        return name in self.obj

    def _get(self, name, default):
        self.queried.add(name)
        if name not in self.obj:
            if default is None:
                raise SceneError(f"'{self.type}' needs the parameter '{name}'", self.loc)
            return default
        return self.obj[name]

    def _loc_of(self, name):
        v = self.obj.get(name)
        return v.get("_loc", self.loc) if isinstance(v, dict) else self.loc

    def float(self, name: str, default: float | None = None) -> float:
        v = self._get(name, default)
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            raise SceneError(f"parameter '{name}' must be a number", self._loc_of(name))
        if not math.isfinite(v):
            raise SceneError(f"parameter '{name}' is not finite", self._loc_of(name))
        return float(v)

    def int(self, name: str, default: int | None = None) -> int:
        v = self._get(name, default)
        if isinstance(v, bool) or not isinstance(v, int):
            raise SceneError(f"parameter '{name}' must be an integer", self._loc_of(name))
        return v

    def bool(self, name: str, default: bool | None = None) -> bool:
        v = self._get(name, default)
        if not isinstance(v, bool):
            raise SceneError(f"parameter '{name}' must be a boolean", self._loc_of(name))
        return v

    def string(self, name: str, default: str | None = None) -> str:
        v = self._get(name, default)
        if not isinstance(v, str):
            raise SceneError(f"parameter '{name}' must be a string", self._loc_of(name))
        return v

    def vec3(self, name: str, default=None) -> np.ndarray:
        v = self._get(name, default)
        a = np.asarray(v, float).reshape(-1)
        if a.size != 3 or not np.all(np.isfinite(a)):
            raise SceneError(f"parameter '{name}' must be 3 finite numbers", self._loc_of(name))
        return a

    def transform(self, name: str = "to_world") -> np.ndarray:
        v = self._get(name, np.eye(4))
        m = np.asarray(v, float)
        if m.shape != (4, 4) or not np.all(np.isfinite(m)):
            raise SceneError(f"parameter '{name}' must be a finite 4x4 transform", self._loc_of(name))
        return m

    def color_or_texture(self, name: str, default=None):
        """An RGB (np.ndarray) or a texture object dict (caller resolves it)."""
        v = self._get(name, default)
        if isinstance(v, dict) and v.get("type") == "ref":
            v = self.resolve(v)
        if isinstance(v, dict) and v.get("type") == "rgb":
            a = np.asarray(v["value"], float)
        elif isinstance(v, dict):
            return v
        else:
            a = np.asarray(v, float).reshape(-1)
            if a.size == 1:
                a = np.repeat(a, 3)
        if a.size != 3 or not np.all(np.isfinite(a)):
            raise SceneError(f"parameter '{name}' must be an RGB value", self._loc_of(name))
        return a

    def rgb(self, name: str, default=None) -> np.ndarray:
        v = self.color_or_texture(name, default)
        if isinstance(v, dict):
            raise SceneError(f"parameter '{name}' must be an RGB value here, not a texture", self._loc_of(name))
        return v

    def resolve(self, v: dict) -> dict:
        if v["id"] not in self.ids:
            raise SceneError(f"reference to unknown id '{v['id']}'", v.get("_loc", self.loc))
        return self.ids[v["id"]]

    def children(self) -> list[dict]:
        """Nested objects (references resolved), marking them as used."""
        out = []
        for k, v in self.obj.items():
            if k in _META or not isinstance(v, dict):
                continue
            if v.get("type") == "ref":
                self.queried.add(k)
                out.append(self.resolve(v))
            elif "_kind" in v or v.get("type") not in (None, "rgb"):
                self.queried.add(k)
                out.append(v)
        return out

    def warn_unqueried(self) -> None:
        for k in self.obj:
            if k not in _META and k not in self.queried:
                warn(f"'{self.type}': unused parameter '{k}'", self._loc_of(k))
