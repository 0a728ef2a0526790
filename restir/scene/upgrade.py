"""Scene files older than Mitsuba 2.0 (the 0.5 / 0.6 format most published scenes are in),
upgraded on load the way Mitsuba 3 upgrades them (src/core/parser.cpp, `upgrade_from_v1`, at
commit b45b0a9):

1. every parameter name goes from camelCase to snake_case (`toWorld` -> `to_world`, `intIOR` ->
   `int_ior`, `maxDepth` -> `max_depth`; `camel_to_snake` states the character rule);
   ids, plugin types, values and `<default>` names are left as written;
2. a `diffuse` BSDF's `diffuse_reflectance` is its `reflectance`;
3. `uoffset`, `voffset`, `uscale`, `vscale` become `to_uv` = scale(uscale, vscale) * translate(uoffset, voffset);
4. the `<lookAt>` transform step is `<lookat>` (Mitsuba 3's first upgrade, src/core/xml.cpp
   before fadd8d6, renamed it; 3.9.1 refuses the element, restir keeps the rename).

Nothing else changes between the formats in Mitsuba 3's upgrade, so anything else a 0.5 file
holds reaches the loader as written and is read, warned about or refused there like any
parameter. The upgrade works on the parsed element tree, before `$name` substitution, so a
substituted value is upgraded like a literal one.
"""
from .errors import SceneError

UV_PARAMETERS = ("uoffset", "voffset", "uscale", "vscale")
CURRENT_MAJOR = 3


def camel_to_snake(name: str) -> str:
    """Mitsuba 3's rule: an uppercase letter right after a lowercase one starts a new word
    (an underscore, then that letter and the uppercase letters after it lowercased); all other
    characters are kept. So `intIOR` -> `int_ior`, `sRGB` -> `s_rgb`, `toWorld2` -> `to_world2`,
    while `uvscale`, `IORValue` and `uv2Scale` stay as they are."""
    out = []
    i = 0
    while i < len(name):
        c = name[i]
        if i > 0 and name[i - 1].islower() and c.isupper():
            out.append("_" + c.lower())
            i += 1
            while i < len(name) and name[i].isupper():
                out.append(name[i].lower())
                i += 1
            continue
        out.append(c)
        i += 1
    return "".join(out)


def parse_version(text: str, loc: str) -> tuple[int, int, int]:
    """A scene's `version` attribute: three numbers, as Mitsuba 3 requires."""
    parts = text.strip().split(".")
    if len(parts) != 3 or not all(p.isdigit() for p in parts):
        raise SceneError(f"version '{text}' is not of the form major.minor.patch (e.g. 3.0.0)", loc)
    return tuple(int(p) for p in parts)


def needs_upgrade(version: tuple[int, int, int], loc: str) -> bool:
    if version[0] > CURRENT_MAJOR:
        raise SceneError(f"scene version {'.'.join(map(str, version))} is newer than the formats restir reads "
                         f"(0.5 to {CURRENT_MAJOR}.x)", loc)
    return version < (2, 0, 0)


def upgrade_v1(node, make_node) -> None:
    """Upgrade a pre-2.0 element tree in place. `make_node(tag, attrib, line)` builds an element
    (the reader's node type)."""
    if node.tag == "lookAt":
        node.tag = "lookat"
    if node.tag != "default" and "name" in node.attrib:
        node.attrib["name"] = camel_to_snake(node.attrib["name"])
    for child in node.children:
        upgrade_v1(child, make_node)
    if node.tag == "bsdf" and node.attrib.get("type") == "diffuse":
        for child in node.children:
            if child.attrib.get("name") == "diffuse_reflectance":
                child.attrib["name"] = "reflectance"
    uv = {c.attrib["name"]: c for c in node.children if c.attrib.get("name") in UV_PARAMETERS and c.tag != "default"}
    if uv:
        line = min(c.line for c in uv.values())
        node.children = [c for c in node.children if c not in uv.values()]

        def value(name, default):
            return uv[name].attrib.get("value", default) if name in uv else default

        # applied in order: translate, then scale (scale * translate, as Mitsuba 3 composes them)
        steps = [make_node("translate", {"x": value("uoffset", "0"), "y": value("voffset", "0")}, line),
                 make_node("scale", {"x": value("uscale", "1"), "y": value("vscale", "1")}, line)]
        transform = make_node("transform", {"name": "to_uv"}, line)
        transform.children = steps
        node.children.append(transform)
