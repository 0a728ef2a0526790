"""Mitsuba 3 XML (and 0.5/0.6 files, upgraded first: upgrade.py) -> nested dict tree (Mitsuba's `load_dict` layout), keeping file:line.

Every object dict has 'type' and '_loc'; parameters are plain values (float, int, bool, str,
np.ndarray for points/vectors, 4x4 np.ndarray for transforms, {'type': 'rgb', 'value': ...});
references are {'type': 'ref', 'id': ...}. Objects with an id are also collected in '_ids'.
"""
import math
import os
import re
import xml.parsers.expat

import numpy as np

from .. import limits
from . import transforms, upgrade
from .errors import SceneError, warn
from .scene_file import read_scene_file

OBJECT_TAGS = {"bsdf", "shape", "emitter", "sensor", "film", "sampler", "integrator", "rfilter", "texture"}
PARAM_TAGS = {"float", "integer", "boolean", "string", "rgb", "spectrum", "point", "vector", "transform", "ref"}
TRANSFORM_OPS = {"matrix", "translate", "rotate", "scale", "lookat"}


class _Node:
    __slots__ = ("tag", "attrib", "children", "line")

    def __init__(self, tag, attrib, line):
        self.tag, self.attrib, self.children, self.line = tag, attrib, [], line


def _parse_xml(path: str) -> _Node:
    data = read_scene_file(path)
    parser = xml.parsers.expat.ParserCreate()
    stack: list[_Node] = []
    root: list[_Node] = []

    def start(tag, attrib):
        if len(stack) >= limits.MAX_XML_DEPTH:
            raise SceneError(f"elements nested more than {limits.MAX_XML_DEPTH} deep",
                             f"{path}:{parser.CurrentLineNumber}")
        node = _Node(tag, attrib, parser.CurrentLineNumber)
        (stack[-1].children if stack else root).append(node)
        stack.append(node)

    def end(tag):
        stack.pop()

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    try:
        parser.Parse(data, True)
    except xml.parsers.expat.ExpatError as e:
        raise SceneError(f"malformed XML: {xml.parsers.expat.ErrorString(e.code)}", f"{path}:{e.lineno}") from None
    return root[0]


def parse_floats(text: str, loc: str, count: int | None = None) -> list[float]:
    parts = [p for p in re.split(r"[,\s]+", text.strip()) if p]
    try:
        vals = [float(p) for p in parts]
    except ValueError:
        raise SceneError(f"cannot parse numbers from '{text}'", loc) from None
    if any(not math.isfinite(v) for v in vals):
        raise SceneError(f"non-finite value in '{text}'", loc)
    if count is not None and len(vals) != count:
        raise SceneError(f"expected {count} numbers, got {len(vals)} in '{text}'", loc)
    return vals


class _Reader:
    def __init__(self, path: str, defines: dict[str, str]):
        self.path = path
        self.defines = dict(defines)   # command-line values win over <default>
        self.cli_defines = set(defines)
        self.used: set[str] = set()    # names substituted somewhere ($name)
        self.ids: dict[str, dict] = {}
        self.auto = 0

    def loc(self, node: _Node) -> str:
        return f"{self.path}:{node.line}"

    def attr(self, node: _Node, name: str, default=None, required=True) -> str:
        if name not in node.attrib:
            if required and default is None:
                raise SceneError(f"<{node.tag}> is missing the '{name}' attribute", self.loc(node))
            return default
        value = node.attrib[name]

        def sub(m):
            key = m.group(1)
            if key not in self.defines:
                raise SceneError(f"undefined parameter '${key}' (add <default name=\"{key}\"> or -D {key}=...)", self.loc(node))
            self.used.add(key)
            return self.defines[key]

        return re.sub(r"\$([A-Za-z_][A-Za-z0-9_]*)", sub, value)

    # -------------------------------------------------------------------- parameters
    def vec3(self, node: _Node) -> np.ndarray:
        if "value" in node.attrib:
            vals = parse_floats(self.attr(node, "value"), self.loc(node))
            if len(vals) == 1:
                vals = vals * 3
            if len(vals) != 3:
                raise SceneError("expected 3 numbers", self.loc(node))
            return np.array(vals)
        return np.array([parse_floats(self.attr(node, k, "0"), self.loc(node), 1)[0] for k in "xyz"])

    def transform(self, node: _Node) -> np.ndarray:
        m = np.eye(4)
        for op in node.children:
            loc = self.loc(op)
            if op.tag not in TRANSFORM_OPS:
                raise SceneError(f"unknown transform operation <{op.tag}>", loc)
            try:
                if op.tag == "matrix":
                    vals = parse_floats(self.attr(op, "value"), loc)
                    if len(vals) == 9:
                        t = np.eye(4)
                        t[:3, :3] = np.array(vals).reshape(3, 3)
                    elif len(vals) == 16:
                        t = np.array(vals).reshape(4, 4)
                    else:
                        raise SceneError("a matrix needs 9 or 16 numbers", loc)
                elif op.tag == "translate":
                    t = transforms.translate(self.vec3(op))
                elif op.tag == "scale":
                    if "value" in op.attrib:
                        t = transforms.scale(self.vec3(op))
                    else:
                        t = transforms.scale([parse_floats(self.attr(op, k, "1"), loc, 1)[0] for k in "xyz"])
                elif op.tag == "rotate":
                    axis = self.vec3(op)
                    angle = parse_floats(self.attr(op, "angle"), loc, 1)[0]
                    t = transforms.rotate(axis, angle)
                else:  # lookat
                    o = parse_floats(self.attr(op, "origin"), loc, 3)
                    tg = parse_floats(self.attr(op, "target"), loc, 3)
                    up = parse_floats(self.attr(op, "up", "0 1 0"), loc, 3)
                    t = transforms.look_at(o, tg, up)
            except ValueError as e:
                raise SceneError(str(e), loc) from None
            m = t @ m
        return m

    def param_value(self, node: _Node):
        loc = self.loc(node)
        tag = node.tag
        if tag == "float":
            return parse_floats(self.attr(node, "value"), loc, 1)[0]
        if tag == "integer":
            v = self.attr(node, "value")
            try:
                return int(v)
            except ValueError:
                raise SceneError(f"'{v}' is not an integer", loc) from None
        if tag == "boolean":
            v = self.attr(node, "value").strip().lower()
            if v not in ("true", "false"):
                raise SceneError(f"'{v}' is not a boolean", loc)
            return v == "true"
        if tag == "string":
            return self.attr(node, "value")
        if tag in ("rgb", "spectrum"):
            vals = parse_floats(self.attr(node, "value"), loc)
            if tag == "spectrum" and len(vals) != 1:
                raise SceneError("only constant <spectrum value=\"v\"> is supported (use <rgb>)", loc)
            if len(vals) == 1:
                vals = vals * 3
            if len(vals) != 3:
                raise SceneError("an rgb value needs 1 or 3 numbers", loc)
            return {"type": "rgb", "value": np.array(vals), "_loc": loc}
        if tag in ("point", "vector"):
            return self.vec3(node)
        if tag == "transform":
            return self.transform(node)
        if tag == "ref":
            return {"type": "ref", "id": self.attr(node, "id"), "_loc": loc}
        raise SceneError(f"unknown element <{tag}>", loc)

    # -------------------------------------------------------------------- objects
    def object(self, node: _Node) -> dict:
        loc = self.loc(node)
        obj = {"type": self.attr(node, "type"), "_loc": loc, "_kind": node.tag}
        if "id" in node.attrib:
            obj["id"] = node.attrib["id"]
        self.fill(obj, node)
        if "id" in obj:
            if obj["id"] in self.ids:
                raise SceneError(f"duplicate id '{obj['id']}'", loc)
            self.ids[obj["id"]] = obj
        return obj

    def fill(self, obj: dict, node: _Node) -> None:
        for child in node.children:
            loc = self.loc(child)
            if child.tag == "default":
                name = self.attr(child, "name")
                if name not in self.cli_defines:
                    self.defines[name] = self.attr(child, "value")
                continue
            if child.tag in OBJECT_TAGS:
                value = self.object(child)
                key = child.attrib.get("name") or child.attrib.get("id") or f"_{child.tag}{self.auto}"
                self.auto += 1
            elif child.tag in PARAM_TAGS:
                value = self.param_value(child)
                key = child.attrib.get("name")
                if key is None:
                    if child.tag != "ref":
                        raise SceneError(f"<{child.tag}> needs a 'name' attribute", loc)
                    key = f"_ref{self.auto}"
                    self.auto += 1
            elif child.tag == "include":
                raise SceneError("<include> is not supported; inline the file", loc)
            else:
                raise SceneError(f"unknown element <{child.tag}>", loc)
            if key in obj:
                raise SceneError(f"parameter '{key}' given twice", loc)
            obj[key] = value
            if isinstance(value, dict):
                value.setdefault("_loc", loc)


def load_xml(path: str, defines: dict[str, str] | None = None, required: set[str] | frozenset = frozenset()) -> dict:
    """Parse a Mitsuba 3 XML file into a scene dict (see module docstring). A define the scene
    never uses is a warning, or an error for the names in `required` (the Python API's keyword
    parameters: a misspelt one would otherwise be silently ignored)."""
    path = os.path.abspath(path) if not os.path.isabs(path) else path
    root = _parse_xml(path)
    reader = _Reader(path, defines or {})
    if root.tag != "scene":
        raise SceneError(f"the root element must be <scene>, not <{root.tag}>", reader.loc(root))
    if "version" not in root.attrib:
        raise SceneError("<scene> needs a version attribute (e.g. version=\"3.0.0\"), as Mitsuba 3 requires: "
                         "the format of the file depends on it", reader.loc(root))
    if upgrade.needs_upgrade(upgrade.parse_version(root.attrib["version"], reader.loc(root)), reader.loc(root)):
        upgrade.upgrade_v1(root, _Node)
    scene = {"type": "scene", "_loc": reader.loc(root), "_kind": "scene"}
    reader.fill(scene, root)
    for name in sorted(reader.cli_defines - reader.used):  # a typo, or a scene without that parameter
        if name in required:
            raise SceneError(f"parameter {name}={reader.defines[name]!r}: the scene never uses '{name}' "
                             f"(no ${name} in it; its parameters are its <default> names)", path)
        warn(f"-D {name}={reader.defines[name]}: the scene never uses '{name}' (no ${name} in it)", path)
    scene["_ids"] = reader.ids
    scene["_base_dir"] = os.path.dirname(path)
    return scene
