"""The pbrt-v4 scene format (docs/guide/pbrt.md): directives read in order with pbrt-v4's
graphics state (the current transform, material, area light and orientation, saved and restored
by AttributeBegin/End), translated into the Mitsuba-style scene object that scene.build_scene
builds. Shapes are read lazily (a PLY file when the builder reaches it, with progress), so every
error in the file itself comes before any mesh is read.
"""
import math
import os

import numpy as np

from ..errors import SceneError, warn
from . import lights, shapes
from .camera import Options
from .materials import Materials, Texture, mask
from .params import ParamSet, read_params
from .tokens import Token, Tokenizer

MAX_INCLUDE_DEPTH = 32
ATTRIBUTE_TARGETS = ("shape", "light", "material", "medium", "texture")


class _State:
    __slots__ = ("ctm", "ctm_end", "active", "reverse", "material", "area_light", "medium", "attributes")

    def __init__(self):
        self.ctm = np.eye(4)
        self.ctm_end = np.eye(4)
        self.active = "all"
        self.reverse = False
        self.material = None       # ("named", name, loc) or ("anon", kind, ParamSet)
        self.area_light = None     # lights.AreaLight
        self.medium = False
        self.attributes: dict[str, dict] = {}  # Attribute "target": its default parameters

    def copy(self) -> "_State":
        s = _State()
        s.ctm, s.ctm_end, s.active = self.ctm.copy(), self.ctm_end.copy(), self.active
        s.reverse, s.material, s.area_light, s.medium = self.reverse, self.material, self.area_light, self.medium
        s.attributes = {k: dict(v) for k, v in self.attributes.items()}
        return s


class _ShapeDef:
    __slots__ = ("load", "ctm", "reverse", "bsdf", "emitter", "loc", "what")

    def __init__(self, load, ctm, reverse, bsdf, emitter, loc, what):
        self.load, self.ctm, self.reverse, self.bsdf, self.emitter = load, ctm, reverse, bsdf, emitter
        self.loc, self.what = loc, what

    def to_dict(self, instance: np.ndarray | None = None) -> dict:
        m = self.ctm if instance is None else instance @ self.ctm
        load, rev = self.load, self.reverse
        d = {"type": "triangles", "load": lambda: load(m, rev), "bsdf": self.bsdf, "_loc": self.loc}
        if self.emitter is not None:
            d["emitter"] = self.emitter
        return d


class PbrtReader:
    def __init__(self, path: str):
        self.path = path
        self.base_dir = os.path.dirname(os.path.abspath(path))
        self.stack: list[Tokenizer] = []
        self.state = _State()
        self.saved: list[tuple] = []   # (state, "attribute" or "transform", loc)
        self.coordinate_systems: dict[str, np.ndarray] = {}
        self.options = Options()
        self.materials = Materials()
        self.named_materials: dict[str, tuple[str, ParamSet]] = {}
        self.media: set[str] = set()
        self.objects: dict[str, list[_ShapeDef]] = {}
        self.current_object: str | None = None
        self.in_world = False
        self.ratio = 1.0
        self.shapes: list[dict] = []
        self.emitters: list[dict] = []
        self.mask_cache: dict = {}

    # ------------------------------------------------------------------ tokens
    def next(self) -> Token | None:
        while self.stack:
            t = self.stack[-1].next()
            if t is not None:
                return t
            self.stack.pop()
        return None

    @property
    def tok(self) -> Tokenizer:
        return self.stack[-1]

    def loc(self, t: Token) -> str:
        return self.tok.loc(t.line)

    def string_arg(self, directive: str, loc: str) -> str:
        t = self.next()
        if t is None or not t.quoted:
            raise SceneError(f"{directive} needs a quoted name", loc)
        return t.text

    def numbers(self, directive: str, count: int, loc: str) -> np.ndarray:
        t = self.next()
        if t is not None and t.text == "[" and not t.quoted:
            values = self.tok.numbers_until_bracket()
            if values is None:
                raise SceneError(f"{directive}: expected {count} numbers in brackets", loc)
        else:
            vals = []
            while t is not None and len(vals) < count:
                try:
                    vals.append(float(t.text))
                except ValueError:
                    break
                if t.quoted:
                    break
                if len(vals) < count:
                    t = self.next()
            values = np.array(vals)
        if len(values) != count or not np.all(np.isfinite(values)):
            raise SceneError(f"{directive} takes {count} finite numbers", loc)
        return values

    # ------------------------------------------------------------------ top level
    def read(self) -> dict:
        self.stack.append(Tokenizer(self.path))
        while True:
            t = self.next()
            if t is None:
                break
            loc = self.loc(t)
            if t.quoted or t.text in ("[", "]"):
                raise SceneError(f"expected a directive, got '{t.text}'", loc)
            handler = getattr(self, "d_" + t.text, None)
            if handler is None:
                raise SceneError(f"unknown directive '{t.text}'", loc)
            handler(loc)
        if self.current_object is not None:
            raise SceneError(f"ObjectBegin '{self.current_object}' without ObjectEnd", self.path)
        if self.saved:
            raise SceneError(f"{len(self.saved)} AttributeBegin without AttributeEnd", self.path)
        if not self.in_world:
            raise SceneError("the file has no WorldBegin", self.path)
        tree = {"type": "scene", "_loc": self.path, "_base_dir": self.base_dir,
                "sensor": self.options.sensor(self.path), "integrator": self.options.integrator()}
        for i, s in enumerate(self.shapes):
            tree[f"shape_{i}"] = s
        for i, e in enumerate(self.emitters):
            tree[f"emitter_{i}"] = e
        return tree

    # ------------------------------------------------------------------ files
    def d_Include(self, loc):
        name = self.string_arg("Include", loc)
        if len(self.stack) >= MAX_INCLUDE_DEPTH:
            raise SceneError(f"Include nested more than {MAX_INCLUDE_DEPTH} deep (does a file include itself?)", loc)
        path = name if os.path.isabs(name) else os.path.join(os.path.dirname(self.path), name)
        if not os.path.exists(path):
            raise SceneError(f"included file '{name}' not found", loc)
        self.stack.append(Tokenizer(path))

    d_Import = d_Include

    # ------------------------------------------------------------------ transforms
    def apply(self, m: np.ndarray, loc: str, replace: bool = False) -> None:
        if self.state.active in ("all", "start"):
            self.state.ctm = m.copy() if replace else self.state.ctm @ m
        if self.state.active in ("all", "end"):
            self.state.ctm_end = m.copy() if replace else self.state.ctm_end @ m

    def d_Identity(self, loc):
        self.apply(np.eye(4), loc, replace=True)

    def d_Translate(self, loc):
        v = self.numbers("Translate", 3, loc)
        m = np.eye(4)
        m[:3, 3] = v
        self.apply(m, loc)

    def d_Scale(self, loc):
        v = self.numbers("Scale", 3, loc)
        self.apply(np.diag([v[0], v[1], v[2], 1.0]), loc)

    def d_Rotate(self, loc):
        a = self.numbers("Rotate", 4, loc)
        axis = a[1:]
        n = np.linalg.norm(axis)
        if n == 0:
            raise SceneError("Rotate: the axis is zero", loc)
        x, y, z = axis / n
        t = math.radians(a[0])
        c, s = math.cos(t), math.sin(t)
        m = np.eye(4)
        m[:3, :3] = [[x * x + (1 - x * x) * c, x * y * (1 - c) - z * s, x * z * (1 - c) + y * s],
                     [x * y * (1 - c) + z * s, y * y + (1 - y * y) * c, y * z * (1 - c) - x * s],
                     [x * z * (1 - c) - y * s, y * z * (1 - c) + x * s, z * z + (1 - z * z) * c]]
        self.apply(m, loc)

    def d_LookAt(self, loc):
        v = self.numbers("LookAt", 9, loc)
        eye, look, up = v[:3], v[3:6], v[6:]
        d = look - eye
        if np.linalg.norm(d) == 0:
            raise SceneError("LookAt: the eye and the point looked at coincide", loc)
        d = d / np.linalg.norm(d)
        right = np.cross(up / max(np.linalg.norm(up), 1e-300), d)
        if np.linalg.norm(right) == 0:
            raise SceneError("LookAt: the up vector is parallel to the view direction", loc)
        right /= np.linalg.norm(right)
        new_up = np.cross(d, right)
        world_from_camera = np.eye(4)
        world_from_camera[:3, 0], world_from_camera[:3, 1], world_from_camera[:3, 2] = right, new_up, d
        world_from_camera[:3, 3] = eye
        self.apply(np.linalg.inv(world_from_camera), loc)

    def d_Transform(self, loc):
        self.apply(self.numbers("Transform", 16, loc).reshape(4, 4).T, loc, replace=True)

    def d_ConcatTransform(self, loc):
        self.apply(self.numbers("ConcatTransform", 16, loc).reshape(4, 4).T, loc)

    def d_CoordinateSystem(self, loc):
        self.coordinate_systems[self.string_arg("CoordinateSystem", loc)] = self.state.ctm.copy()

    def d_CoordSysTransform(self, loc):
        name = self.string_arg("CoordSysTransform", loc)
        if name not in self.coordinate_systems:
            raise SceneError(f"unknown coordinate system '{name}'", loc)
        self.apply(self.coordinate_systems[name], loc, replace=True)

    def d_ActiveTransform(self, loc):
        t = self.next()
        if t is None or t.text not in ("StartTime", "EndTime", "All"):
            raise SceneError("ActiveTransform takes StartTime, EndTime or All", loc)
        self.state.active = {"StartTime": "start", "EndTime": "end", "All": "all"}[t.text]

    def d_TransformTimes(self, loc):
        self.numbers("TransformTimes", 2, loc)

    def d_ReverseOrientation(self, loc):
        self.state.reverse = not self.state.reverse

    def ctm_now(self, what: str, loc: str) -> np.ndarray:
        if not np.allclose(self.state.ctm, self.state.ctm_end, rtol=0, atol=1e-12):
            raise SceneError(f"{what}: an animated transform (motion blur) is not supported", loc)
        return self.state.ctm.copy()

    # ------------------------------------------------------------------ blocks
    def d_AttributeBegin(self, loc):
        self.saved.append((self.state.copy(), "attribute", loc))

    def d_AttributeEnd(self, loc):
        if not self.saved or self.saved[-1][1] != "attribute":
            raise SceneError("AttributeEnd without AttributeBegin", loc)
        self.state = self.saved.pop()[0]

    def d_TransformBegin(self, loc):  # pbrt-v3's, still read by pbrt-v4
        self.saved.append((self.state.copy(), "transform", loc))

    def d_TransformEnd(self, loc):
        if not self.saved or self.saved[-1][1] != "transform":
            raise SceneError("TransformEnd without TransformBegin", loc)
        old = self.saved.pop()[0]
        self.state.ctm, self.state.ctm_end, self.state.active = old.ctm, old.ctm_end, old.active

    def d_Attribute(self, loc):
        """Default parameters for the directives of one kind (shape, light, material, medium,
        texture) until the attribute block ends; a directive's own parameters win."""
        target = self.string_arg("Attribute", loc)
        if target not in ATTRIBUTE_TARGETS:
            raise SceneError(f"Attribute: unknown target '{target}' (one of {', '.join(ATTRIBUTE_TARGETS)})", loc)
        ps = read_params(self.tok, f"Attribute \"{target}\"", loc)
        self.state.attributes.setdefault(target, {}).update(ps.params)

    def params(self, target: str, what: str, loc: str) -> ParamSet:
        return read_params(self.tok, what, loc).with_defaults(self.state.attributes.get(target, {}))

    def d_ObjectBegin(self, loc):
        name = self.string_arg("ObjectBegin", loc)
        if self.current_object is not None:
            raise SceneError("ObjectBegin inside another ObjectBegin", loc)
        if name in self.objects:
            raise SceneError(f"object '{name}' defined twice", loc)
        self.d_AttributeBegin(loc)
        self.current_object = name
        self.objects[name] = []

    def d_ObjectEnd(self, loc):
        if self.current_object is None:
            raise SceneError("ObjectEnd without ObjectBegin", loc)
        self.current_object = None
        self.d_AttributeEnd(loc)

    def d_ObjectInstance(self, loc):
        name = self.string_arg("ObjectInstance", loc)
        if self.current_object is not None:
            raise SceneError("ObjectInstance inside ObjectBegin", loc)
        if name not in self.objects:
            raise SceneError(f"unknown object '{name}'", loc)
        m = self.ctm_now("ObjectInstance", loc)
        for sd in self.objects[name]:
            self.shapes.append(sd.to_dict(m))

    # ------------------------------------------------------------------ options
    def options_directive(self, name: str, loc: str, with_type: bool = True):
        if self.in_world:
            raise SceneError(f"{name} must come before WorldBegin", loc)
        kind = self.string_arg(name, loc) if with_type else None
        return kind, read_params(self.tok, f"{name} \"{kind}\"" if kind else name, loc)

    def d_Camera(self, loc):
        kind, ps = self.options_directive("Camera", loc)
        if kind != "perspective":
            raise SceneError(f"Camera '{kind}' is not supported (perspective only)", loc)
        if self.options.camera is not None:
            raise SceneError("a second Camera", loc)
        ctm = self.ctm_now("Camera", loc)
        self.options.camera = (ps, ctm)
        try:
            self.coordinate_systems["camera"] = np.linalg.inv(ctm)
        except np.linalg.LinAlgError:
            raise SceneError("Camera: the transform before it is singular", loc) from None

    def d_Film(self, loc):
        kind, ps = self.options_directive("Film", loc)
        if kind != "rgb":
            warn(f"Film '{kind}' is rendered as an rgb film", loc)
        self.options.film = ps

    def d_PixelFilter(self, loc):
        self.options.filter = self.options_directive("PixelFilter", loc)

    def d_Sampler(self, loc):
        self.options.sampler = self.options_directive("Sampler", loc)

    def d_Integrator(self, loc):
        self.options.integrator_spec = self.options_directive("Integrator", loc)

    def d_Accelerator(self, loc):  # restir builds its own acceleration structure
        ps = self.options_directive("Accelerator", loc)[1]
        ps.ignore(*ps.params)

    def d_ColorSpace(self, loc):
        name = self.string_arg("ColorSpace", loc)
        if name != "srgb":
            raise SceneError(f"ColorSpace '{name}' is not supported (srgb only)", loc)

    def d_Option(self, loc):
        ps = read_params(self.tok, "Option", loc)
        for name in ps.params:
            warn(f"Option '{name}' has no effect in restir", ps.loc_of(name))
            ps.ignore(name)

    def d_WorldBegin(self, loc):
        if self.in_world:
            raise SceneError("a second WorldBegin", loc)
        self.in_world = True
        self.ratio = self.options.imaging_ratio()
        self.state.ctm, self.state.ctm_end = np.eye(4), np.eye(4)
        self.coordinate_systems["world"] = np.eye(4)

    def d_WorldEnd(self, loc):  # pbrt-v3's end of the file
        pass

    # ------------------------------------------------------------------ world
    def world(self, name: str, loc: str) -> None:
        if not self.in_world:
            raise SceneError(f"{name} must come after WorldBegin", loc)

    def d_MakeNamedMedium(self, loc):
        name = self.string_arg("MakeNamedMedium", loc)
        ps = self.params("medium", f"MakeNamedMedium \"{name}\"", loc)
        ps.ignore(*ps.params)
        self.media.add(name)
        warn(f"participating medium '{name}' is not rendered (restir has no media): the surfaces around it render "
             "as if it held vacuum", loc)

    def d_MediumInterface(self, loc):
        names = [self.string_arg("MediumInterface", loc)]
        t = self.next()
        if t is not None and t.quoted:
            names.append(t.text)
        elif t is not None:
            self.tok.push(t)
        for n in names:
            if n and n not in self.media:
                raise SceneError(f"unknown medium '{n}'", loc)

    def d_Texture(self, loc):
        self.world("Texture", loc)
        name = self.string_arg("Texture", loc)
        type_ = self.string_arg("Texture", loc)
        cls = self.string_arg("Texture", loc)
        ps = self.params("texture", f"Texture \"{name}\"", loc)
        self.materials.define_texture(Texture(name, type_, cls, ps, self.base_dir))

    def d_Material(self, loc):
        self.world("Material", loc)
        kind = self.string_arg("Material", loc)
        self.state.material = ("anon", kind, self.params("material", f"Material \"{kind}\"", loc))

    def d_MakeNamedMaterial(self, loc):
        self.world("MakeNamedMaterial", loc)
        name = self.string_arg("MakeNamedMaterial", loc)
        ps = self.params("material", f"MakeNamedMaterial \"{name}\"", loc)
        if name in self.named_materials:
            raise SceneError(f"named material '{name}' defined twice", loc)
        kind = ps.string("type")
        if kind is None:
            raise SceneError(f"MakeNamedMaterial \"{name}\" needs 'string type'", loc)
        self.named_materials[name] = (kind, ps)

    def d_NamedMaterial(self, loc):
        self.world("NamedMaterial", loc)
        self.state.material = ("named", self.string_arg("NamedMaterial", loc), loc)

    def named_material(self, name: str, loc: str) -> dict | None:
        if name not in self.named_materials:
            raise SceneError(f"unknown named material '{name}'", loc)
        kind, ps = self.named_materials[name]
        return self.materials.material(kind, ps, ("named", name), self.named_material)

    def current_material(self) -> dict | None:
        m = self.state.material
        if m is None:
            key, kind, ps = "default", "diffuse", ParamSet({}, self.path, self.path, "default material")
        elif m[0] == "named":
            if m[1] not in self.named_materials:
                raise SceneError(f"unknown named material '{m[1]}'", m[2])
            kind, ps = self.named_materials[m[1]]
            key = ("named", m[1])
        else:
            kind, ps = m[1], m[2]
            key = ("anon", id(ps))
        return self.materials.material(kind, ps, key, self.named_material)

    def d_LightSource(self, loc):
        self.world("LightSource", loc)
        kind = self.string_arg("LightSource", loc)
        ps = self.params("light", f"LightSource \"{kind}\"", loc)
        if self.current_object is not None:
            raise SceneError("a LightSource inside ObjectBegin is not supported", loc)
        self.emitters.append(lights.light_source(kind, ps, self.ctm_now("LightSource", loc), self.ratio, self.base_dir))

    def d_AreaLightSource(self, loc):
        self.world("AreaLightSource", loc)
        kind = self.string_arg("AreaLightSource", loc)
        ps = self.params("light", f"AreaLightSource \"{kind}\"", loc)
        self.state.area_light = lights.AreaLight(kind, ps, self.ratio)

    def d_Shape(self, loc):
        self.world("Shape", loc)
        kind = self.string_arg("Shape", loc)
        ps = self.params("shape", f"Shape \"{kind}\"", loc)
        load, object_area = shapes.read_shape(kind, ps, self.base_dir)
        alpha_tex = ps.texture("alpha")
        alpha = 1.0 if alpha_tex is not None else ps.float("alpha", 1.0)
        if not 0 <= alpha <= 1:
            raise SceneError("Shape: alpha must be in [0, 1]", ps.loc_of("alpha"))
        ps.warn_unused()
        ctm = self.ctm_now("Shape", loc)
        bsdf = self.current_material()
        light = self.state.area_light
        if bsdf is None:  # interface: the surface only bounds media, which restir does not render
            if light is not None:
                raise SceneError("an area light on a shape with the 'interface' material", loc)
            return
        if alpha_tex is not None or alpha < 1:
            key = (id(bsdf), alpha_tex, alpha)
            if key not in self.mask_cache:
                opacity = (self.materials.texture(alpha_tex, "float", ps.loc_of("alpha")) if alpha_tex is not None
                           else np.full(3, alpha))
                self.mask_cache[key] = mask(bsdf, opacity)
            bsdf = self.mask_cache[key]
        emitter = None
        if light is not None:
            if self.current_object is not None:
                raise SceneError("an area light inside ObjectBegin is not supported (as in pbrt-v4)", loc)
            area = None
            if light.phi:
                mesh = load(ctm, self.state.reverse)
                p = mesh.positions
                area = float(0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1).sum())
            emitter = light.emitter(area)
        sd = _ShapeDef(load, ctm, self.state.reverse, bsdf, emitter, loc, kind)
        if self.current_object is not None:
            self.objects[self.current_object].append(sd)
        else:
            self.shapes.append(sd.to_dict())


def load_pbrt(path: str) -> dict:
    """A pbrt-v4 file as a scene object for scene.build_scene."""
    return PbrtReader(path).read()
