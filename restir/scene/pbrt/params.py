"""A pbrt-v4 directive's parameter list (`"float fov" [ 45 ]`): typed access, and a warning for
every parameter the loader never read (a misspelt name would otherwise be ignored in silence).
"""
import numpy as np

from ..errors import SceneError, warn
from .tokens import Tokenizer

# pbrt-v4's parameter types; `color` and `normal3` are older spellings pbrt-v4 still reads
NUMBER_TYPES = {"integer": 1, "float": 1, "point2": 2, "vector2": 2, "point3": 3, "vector3": 3, "point": 3,
                "vector": 3, "normal": 3, "normal3": 3, "rgb": 3, "color": 3, "blackbody": 1}
STRING_TYPES = ("string", "texture", "spectrum", "bool")
SPECTRUM_TYPES = ("rgb", "color", "blackbody", "spectrum")


class Param:
    __slots__ = ("type", "name", "values", "line")

    def __init__(self, type_: str, name: str, values, line: int):
        self.type, self.name, self.values, self.line = type_, name, values, line


class ParamSet:
    """The parameters of one directive, by name; `loc` is the directive's file:line."""

    def __init__(self, params: dict[str, Param], path: str, loc: str, what: str):
        self.params, self.path, self.loc, self.what = params, path, loc, what
        self.used: set[str] = set()
        self.defaulted: set[str] = set()

    def loc_of(self, name: str) -> str:
        p = self.params.get(name)
        return f"{self.path}:{p.line}" if p is not None else self.loc

    def has(self, name: str) -> bool:
        return name in self.params

    def type_of(self, name: str) -> str | None:
        p = self.params.get(name)
        return None if p is None else p.type

    def _get(self, name: str, types: tuple, what: str) -> Param | None:
        p = self.params.get(name)
        if p is None:
            return None
        self.used.add(name)
        if p.type not in types:
            raise SceneError(f"{self.what}: '{name}' must be {what}, not '{p.type}'", self.loc_of(name))
        return p

    def _one(self, p: Param):
        if len(p.values) != 1:
            raise SceneError(f"{self.what}: '{p.name}' takes one value, not {len(p.values)}", self.loc_of(p.name))
        return p.values[0]

    def float(self, name: str, default: float | None = None) -> float | None:
        p = self._get(name, ("float",), "a float")
        if p is None:
            return default
        return float(self._one(p))

    def int(self, name: str, default: int | None = None) -> int | None:
        p = self._get(name, ("integer",), "an integer")
        if p is None:
            return default
        return int(self._one(p))

    def bool(self, name: str, default: bool | None = None) -> bool | None:
        p = self._get(name, ("bool",), "a bool")
        if p is None:
            return default
        return self._one(p)

    def string(self, name: str, default: str | None = None) -> str | None:
        p = self._get(name, ("string",), "a string")
        if p is None:
            return default
        return self._one(p)

    def strings(self, name: str) -> list[str] | None:
        p = self._get(name, ("string",), "strings")
        return None if p is None else list(p.values)

    def texture(self, name: str) -> str | None:
        """The texture named by a `texture` parameter (None when the parameter is absent or not one)."""
        if self.type_of(name) != "texture":
            return None
        return self._one(self._get(name, ("texture",), "a texture"))

    def array(self, name: str, types: tuple, width: int) -> np.ndarray | None:
        """A list of numbers of one of `types`, as (N, width) (N x 1 for scalars)."""
        p = self._get(name, types, " or ".join(types))
        if p is None:
            return None
        a = p.values
        if len(a) % width:
            raise SceneError(f"{self.what}: '{name}' holds {len(a)} numbers, not a multiple of {width}",
                             self.loc_of(name))
        return a.reshape(-1, width)

    def ints(self, name: str) -> np.ndarray | None:
        a = self.array(name, ("integer",), 1)
        return None if a is None else a.reshape(-1).astype(np.int64)

    def floats(self, name: str) -> np.ndarray | None:
        a = self.array(name, ("float",), 1)
        return None if a is None else a.reshape(-1)

    def point3(self, name: str, default=None) -> np.ndarray | None:
        a = self.array(name, ("point3", "point", "vector3", "vector", "normal", "normal3"), 3)
        if a is None:
            return None if default is None else np.asarray(default, float)
        if len(a) != 1:
            raise SceneError(f"{self.what}: '{name}' takes one point, not {len(a)}", self.loc_of(name))
        return a[0]

    def spectrum(self, name: str):
        """A spectrum-valued parameter as written: ("rgb", (3,)), ("blackbody", kelvin),
        ("spectrum", (N, 2) wavelength-value pairs) or ("named", name); None when absent."""
        p = self._get(name, SPECTRUM_TYPES, "a spectrum (rgb, blackbody or spectrum)")
        if p is None:
            return None
        if p.type in ("rgb", "color"):
            if len(p.values) != 3:
                raise SceneError(f"{self.what}: '{name}' takes 3 numbers", self.loc_of(name))
            return "rgb", np.asarray(p.values, float)
        if p.type == "blackbody":
            return "blackbody", float(self._one(p))
        if len(p.values) == 1 and isinstance(p.values[0], str):
            return "named", p.values[0]
        if isinstance(p.values, np.ndarray) and len(p.values) >= 2 and len(p.values) % 2 == 0:
            return "spectrum", p.values.reshape(-1, 2)
        raise SceneError(f"{self.what}: spectrum '{name}' must be wavelength-value pairs, a named spectrum or a "
                         "file (spectrum files are not supported)", self.loc_of(name))

    def with_defaults(self, defaults: dict) -> "ParamSet":
        """The `Attribute` directive's parameters for this kind of directive, under its own: a
        default is never warned about when unused (it applies to every directive of the kind)."""
        for name, p in defaults.items():
            if name not in self.params:
                self.params[name] = p
                self.defaulted.add(name)
        return self

    def ignore(self, *names: str) -> None:
        """Parameters read and deliberately without effect here (their reason is in the docs)."""
        self.used.update(n for n in names if n in self.params)

    def warn_unused(self) -> None:
        for name in self.params:
            if name not in self.used and name not in self.defaulted:
                warn(f"{self.what}: unused parameter '{self.params[name].type} {name}'", self.loc_of(name))


def read_params(tok: Tokenizer, what: str, loc: str) -> ParamSet:
    """The parameters after a directive's positional arguments, up to the next directive."""
    params: dict[str, Param] = {}
    while True:
        t = tok.next()
        if t is None:
            break
        if not t.quoted:
            tok.push(t)
            break
        decl = t.text.split()
        if len(decl) != 2:
            raise SceneError(f"{what}: expected a parameter declaration \"type name\", got \"{t.text}\"",
                             tok.loc(t.line))
        type_, name = decl
        if type_ not in NUMBER_TYPES and type_ not in STRING_TYPES:
            raise SceneError(f"{what}: unknown parameter type '{type_}' (of '{name}')", tok.loc(t.line))
        if name in params:
            raise SceneError(f"{what}: parameter '{name}' given twice", tok.loc(t.line))
        params[name] = Param(type_, name, _values(tok, type_, name, what), t.line)
    return ParamSet(params, tok.path, loc, what)


def _values(tok: Tokenizer, type_: str, name: str, what: str):
    first = tok.next()
    if first is None:
        raise SceneError(f"{what}: parameter '{name}' has no value", tok.loc())
    line = first.line
    if first.text == "[" and not first.quoted:
        fast = tok.numbers_until_bracket() if type_ in NUMBER_TYPES or type_ == "spectrum" else None
        if fast is not None:
            raw = fast
        else:
            raw = []
            while True:
                t = tok.next()
                if t is None:
                    raise SceneError(f"{what}: parameter '{name}': '[' without ']'", tok.loc(line))
                if t.text == "]" and not t.quoted:
                    break
                raw.append(t)
    else:
        raw = [first]
    loc = tok.loc(line)
    if isinstance(raw, np.ndarray):
        values = raw
    elif type_ in NUMBER_TYPES or (type_ == "spectrum" and raw and not raw[0].quoted):
        if any(t.quoted for t in raw):
            raise SceneError(f"{what}: '{type_} {name}' takes numbers, not strings", loc)
        values = np.empty(len(raw), np.float64)
        for i, t in enumerate(raw):
            try:
                values[i] = float(t.text)
            except ValueError:
                raise SceneError(f"{what}: '{type_} {name}': '{t.text}' is not a number", loc) from None
    elif type_ == "bool":
        values = []
        for t in raw:
            if t.text not in ("true", "false"):
                raise SceneError(f"{what}: bool '{name}' must be true or false, not '{t.text}'", loc)
            values.append(t.text == "true")
    else:
        if any(not t.quoted for t in raw):
            raise SceneError(f"{what}: '{type_} {name}' takes quoted strings", loc)
        values = [t.text for t in raw]
    if isinstance(values, np.ndarray):
        if not np.all(np.isfinite(values)):
            raise SceneError(f"{what}: '{name}' holds a value that is not finite", loc)
        if type_ == "integer" and np.any(values != np.round(values)):
            raise SceneError(f"{what}: integer '{name}' holds a number that is not an integer", loc)
    if len(values) == 0:
        raise SceneError(f"{what}: parameter '{name}' has no value", loc)
    return values

