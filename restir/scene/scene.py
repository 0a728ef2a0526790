"""Host scene: built from a scene dict (XML or builtin), converted to a SceneDevice for kernels."""
import math
import os
from dataclasses import dataclass, field

import numpy as np

from .. import limits
from . import shapes as shape_lib
from .delta_lights import FALLOFFS, DeltaLightDesc
from .errors import SceneError, warn
from .props import Props
from .textures import FILTERS, WRAPS, TextureDesc, uv_transform
from .transforms import transform_normals, transform_points

KINDS = {
    "bsdf": {"diffuse", "conductor", "roughconductor", "dielectric", "thindielectric", "roughdielectric", "plastic",
             "roughplastic", "twosided", "bumpmap", "normalmap", "mask", "mixture", "metallic_roughness",
             "diffuse_transmission"},
    "shape": {"obj", "ply", "rectangle", "cube", "disk", "sphere", "trimesh", "triangles"},
    "emitter": {"area", "constant", "envmap", "point", "spot", "directional"},
    "sensor": {"perspective", "thinlens"},
    "film": {"hdrfilm"},
    "rfilter": {"box", "tent", "gaussian"},
    "sampler": {"independent", "stratified", "multijitter", "orthogonal", "ldsampler"},
    "integrator": {"path", "direct", "volpath", "path_guiding_integrator", "aov"},
    "texture": {"bitmap", "checkerboard"},
}
TYPE_TO_KIND = {t: k for k, ts in KINDS.items() for t in ts}
PERTURBING = ("bumpmap", "normalmap")  # the BSDFs that tilt their nested BSDF's shading normal (device/bump.py)
DELTA_EMITTERS = ("point", "spot", "directional")  # emitters at a point or from one direction (delta_light)

# Mitsuba's named IORs (src/render/ior.h).
IOR_TABLE = {
    "vacuum": 1.0, "helium": 1.000036, "hydrogen": 1.000132, "air": 1.000277, "carbon dioxide": 1.00045,
    "water": 1.3330, "acetone": 1.36, "ethanol": 1.361, "carbon tetrachloride": 1.461, "glycerol": 1.4729,
    "benzene": 1.501, "silicone oil": 1.52045, "bromine": 1.661, "water ice": 1.31, "fused quartz": 1.458,
    "pyrex": 1.470, "acrylic glass": 1.49, "polypropylene": 1.49, "bk7": 1.5046, "sodium chloride": 1.544,
    "amber": 1.55, "pet": 1.5750, "diamond": 2.419,
}


# The parameters a texture may drive, in the order of SceneDevice.material_textures' components;
# the loader reads the spectra with `spectrum()`, a mask's opacity (a scalar: the texture's
# luminance) in `mask()`, a rough conductor's or dielectric's alpha (`roughness`, a scalar) in
# `material_desc`, a mixture's amount in `mixture()`; the device resolves them in
# `scene_device.textured_material` and `material_index_at`.
TEXTURED_SPECTRA = ("reflectance", "specular_reflectance", "specular_transmittance")
TEXTURED_PARAMETERS = TEXTURED_SPECTRA + ("opacity", "roughness", "amount", "metallic")


@dataclass
class BumpDesc:
    """Mitsuba 3's `bumpmap` or `normalmap` around a material (device/bump.py): its height or
    normal texture's index."""
    texture: int
    scale: float = 1.0         # a bump map's height scale; a normal map's `strength`
    flip_invalid_normals: bool = True
    use_shadowing_function: bool = True
    kind: str = "height"       # "height" (bumpmap) or "normal" (normalmap)
    uv_handed: bool = False    # a normal map's bitangent follows the uv mapping's orientation


@dataclass
class MaterialDesc:
    kind: str
    twosided: bool = False
    reflectance: np.ndarray = field(default_factory=lambda: np.full(3, 0.5))
    textures: dict = field(default_factory=dict)  # parameter (one of TEXTURED_PARAMETERS) -> texture index
    specular_reflectance: np.ndarray = field(default_factory=lambda: np.ones(3))
    specular_transmittance: np.ndarray = field(default_factory=lambda: np.ones(3))
    eta: np.ndarray = field(default_factory=lambda: np.zeros(3))
    k: np.ndarray = field(default_factory=lambda: np.ones(3))
    ior: float = 1.5046 / 1.000277
    distribution: str = "beckmann"
    alpha_u: float = 0.1
    alpha_v: float = 0.1
    specular_sampling_weight: float = 0.5
    fdr_int: float = 0.0
    nonlinear: bool = False
    coat_transmittance: np.ndarray | None = None
    bump: BumpDesc | None = None
    masked: bool = False       # Mitsuba 3's `mask` around the material (bsdf.py: the null lobe)
    opacity: float = 1.0       # its constant opacity (textured: textures["opacity"])
    roughness_remap: int = 0   # a textured roughness: alpha (0), pbrt-v4's (1: alpha = sqrt) or glTF's (2: r^2)
    metallic: float = 0.0      # metallic_roughness (glTF): the metal fraction (textured: textures["metallic"])
    mix: tuple[int, int] | None = None  # a mixture (pbrt-v4's `mix`): its two materials' indices
    mix_amount: float = 0.0    # the probability of the second (textured: textures["amount"])


def fresnel_diffuse_reflectance(eta: float) -> float:
    """Hemispherical average of dielectric Fresnel reflectance: published fits, as Mitsuba uses
    (Egan and Hilgeman 1973 for eta < 1; d'Eon and Irving 2011 otherwise)."""
    if eta < 1.0:
        return -1.4399 * eta * eta + 0.7099 * eta + 0.6681 + 0.0636 / eta
    x = 1.0 / eta
    return 0.919317 + x * (-3.4793 + x * (6.75335 + x * (-7.80989 + x * (4.98554 + x * -1.36881))))


@dataclass
class CameraDesc:
    to_world: np.ndarray
    fov: float
    fov_axis: str
    width: int
    height: int
    filter: str = "gaussian"
    filter_radius: float = 2.0
    filter_stddev: float = 0.5
    aperture_radius: float = 0.0   # thin lens (Mitsuba 3's `thinlens`); 0: a pinhole
    focus_distance: float = 1.0e4  # the distance of the plane in focus, along the view axis

    def tan_half(self) -> tuple[float, float]:
        aspect = self.width / self.height
        t = math.tan(math.radians(self.fov) / 2)
        axis = self.fov_axis
        if axis == "smaller":
            axis = "x" if self.width <= self.height else "y"
        elif axis == "larger":
            axis = "x" if self.width >= self.height else "y"
        if axis == "x":
            return t, t / aspect
        if axis == "y":
            return t * aspect, t
        # diagonal: the fov spans the image diagonal
        d = t / math.sqrt(1 + 1 / (aspect * aspect))
        return d, d / aspect


@dataclass
class Scene:
    name: str
    positions: np.ndarray       # (T, 3, 3) float32, world space
    normals: np.ndarray         # (T, 3, 3)
    uvs: np.ndarray             # (T, 3, 2)
    tri_smooth: np.ndarray      # (T,) int32
    tri_material: np.ndarray    # (T,) int32
    tri_emission: np.ndarray    # (T, 3)
    materials: list[MaterialDesc]
    camera: CameraDesc
    spp: int = 16
    max_depth: int = -1
    rr_depth: int = 5
    hide_emitters: bool = False
    env_kind: str = "none"
    env_radiance: np.ndarray = field(default_factory=lambda: np.zeros(3))
    env_to_world: np.ndarray = field(default_factory=lambda: np.eye(3))
    env_image: np.ndarray | None = None
    textures: list[TextureDesc] = field(default_factory=list)
    delta_lights: list[DeltaLightDesc] = field(default_factory=list)
    tri_emit_twosided: np.ndarray | None = None  # (T,) bool: an area emitter that emits from both sides
    tangents: np.ndarray | None = None  # (T, 3, 4): normal maps' given tangents and bitangent signs (sign 0: none)
    # named objects an animation can move: a shape's triangles [start, stop), a delta light's index
    objects: dict = field(default_factory=dict)
    delta_light_names: dict = field(default_factory=dict)
    animation: object = None  # scene/animation.py Animation, or None: a static scene

    @property
    def num_triangles(self) -> int:
        return len(self.positions)

    def triangle_areas(self) -> np.ndarray:
        p = self.positions.astype(np.float64)
        return 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)

    def light_power(self) -> np.ndarray:
        """Per-triangle emitted power up to the constant pi (luminance * area; twice that for a
        two-sided emitter)."""
        lum = self.tri_emission @ np.array([0.2126, 0.7152, 0.0722])
        sides = 1.0 if self.tri_emit_twosided is None else 1.0 + self.tri_emit_twosided
        return np.maximum(lum, 0) * self.triangle_areas() * sides

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        p = self.positions.reshape(-1, 3)
        return p.min(0), p.max(0)

    def bounding_radius(self) -> float:
        """The radius of the sphere around the bounding box (a directional light's power)."""
        lo, hi = self.bounds()
        return float(0.5 * np.linalg.norm(hi.astype(np.float64) - lo))

    def delta_light_power(self) -> np.ndarray:
        """Per delta light, its power in light_power's units (scene/delta_lights.py)."""
        r = self.bounding_radius()
        return np.array([d.power(r) for d in self.delta_lights], np.float64)


# ----------------------------------------------------------------------------- builder
MISSING_TEXTURES = ("error", "grey")  # what a bitmap whose file is missing becomes (load_scene's option)
MISSING_GREY = 0.5


class _Builder:
    def __init__(self, tree: dict, name: str, missing_textures: str = "error", progress=None):
        if missing_textures not in MISSING_TEXTURES:
            raise SceneError(f"missing_textures must be one of {', '.join(MISSING_TEXTURES)}, not '{missing_textures}'")
        self.missing_textures = missing_textures
        self.progress = progress
        self.tree = tree
        self.name = name
        self.ids = tree.get("_ids", {})
        self.base_dir = tree.get("_base_dir", os.getcwd())
        self.materials: list[MaterialDesc] = []
        self.bump_wrappers: list[dict] = []  # top-level bumpmaps (a warning if only their BSDF is used)
        self.material_index: dict[int, int] = {}
        self.textures: list[TextureDesc] = []
        self.parts: list[tuple] = []
        self.env = None
        self.camera = None
        self.spp = 16
        self.max_depth = -1
        self.rr_depth = 5
        self.delta_lights: list[DeltaLightDesc] = []
        self.hide_emitters = False

    def props(self, obj: dict, kind: str) -> Props:
        t = obj.get("type")
        k = obj.get("_kind") or TYPE_TO_KIND.get(t)
        loc = obj.get("_loc")
        if k is None or t not in KINDS.get(k, ()):
            raise SceneError(f"unsupported {kind} plugin type '{t}'", loc)
        if k != kind:
            raise SceneError(f"expected a {kind}, got a {k} of type '{t}'", loc)
        return Props(obj, self.ids)

    @staticmethod
    def kind_of(obj: dict) -> str:
        k = obj.get("_kind") or TYPE_TO_KIND.get(obj.get("type"))
        if k is None:
            raise SceneError(f"unsupported plugin type '{obj.get('type')}'", obj.get("_loc"))
        return k

    # --------------------------------------------------------------- top level
    def build(self) -> Scene:
        root = Props(self.tree, self.ids)
        children = root.children()
        names = {id(v): k for k, v in self.tree.items() if isinstance(v, dict)}
        objects, delta_names, tris = {}, {}, 0
        for done, obj in enumerate(children):
            if self.progress is not None:
                self.progress(done, len(children))
            kind = self.kind_of(obj)
            name = obj.get("id") or names.get(id(obj), "")
            if kind == "shape":
                first = len(self.parts)
                self.shape(obj)
                added = sum(len(p[0]) for p in self.parts[first:])
                if name and not name.startswith("_") and added:
                    objects[name] = (tris, tris + added)
                tris += added
            elif kind == "emitter" and obj.get("type") in DELTA_EMITTERS:
                if name and not name.startswith("_"):
                    delta_names[name] = len(self.delta_lights)
                self.delta_lights.append(self.delta_light(obj))
            elif kind == "emitter":
                self.environment(obj)
            elif kind == "sensor":
                self.sensor(obj)
            elif kind == "integrator":
                self.integrator(obj)
            elif kind in ("bsdf", "texture"):
                # declared with an id for reference; built when a shape uses it
                if obj.get("type") in PERTURBING:
                    self.bump_wrappers.append(obj)
            else:
                raise SceneError(f"a {kind} cannot appear at the top level", obj.get("_loc"))
        if self.progress is not None:
            self.progress(len(children), len(children))
        self.warn_unapplied_bumps()
        if self.camera is None:
            raise SceneError("the scene has no <sensor>", self.tree.get("_loc"))
        if not self.parts:
            raise SceneError("the scene has no shapes", self.tree.get("_loc"))
        pos = np.concatenate([p[0] for p in self.parts]).astype(np.float32)
        nrm = np.concatenate([p[1] for p in self.parts]).astype(np.float32)
        uvs = np.concatenate([p[2] for p in self.parts]).astype(np.float32)
        smooth = np.concatenate([np.full(len(p[0]), p[3], np.int32) for p in self.parts])
        mat = np.concatenate([np.full(len(p[0]), p[4], np.int32) for p in self.parts])
        emis = np.concatenate([p[5] if np.ndim(p[5]) == 2 else np.tile(p[5], (len(p[0]), 1))
                               for p in self.parts]).astype(np.float32)
        twosided = None
        if any(p[6] for p in self.parts):
            twosided = np.concatenate([np.full(len(p[0]), p[6], bool) for p in self.parts])
        tangents = None
        if any(p[7] is not None for p in self.parts):  # sign 0: no tangent given (derived from the uvs)
            tangents = np.concatenate([p[7] if p[7] is not None else np.zeros((len(p[0]), 3, 4))
                                       for p in self.parts]).astype(np.float32)
        env_kind, env_rad, env_rot, env_img = self.env or ("none", np.zeros(3), np.eye(3), None)
        return Scene(self.name, pos, nrm, uvs, smooth, mat, emis, self.materials, self.camera,
                     self.spp, self.max_depth, self.rr_depth, self.hide_emitters,
                     env_kind, env_rad, env_rot, env_img, self.textures, self.delta_lights, twosided, tangents,
                     objects, delta_names)

    def integrator(self, obj):
        p = self.props(obj, "integrator")
        if p.type != "path":
            warn(f"integrator '{p.type}' is rendered with restir's own methods (max_depth is kept)", p.loc)
        self.max_depth = p.int("max_depth", -1)
        self.rr_depth = p.int("rr_depth", 5)
        self.hide_emitters = p.bool("hide_emitters", False)
        problem = limits.depth_problem(self.max_depth)
        if problem:
            raise SceneError(problem, p.loc)
        p.warn_unqueried()

    def sensor(self, obj):
        if self.camera is not None:
            raise SceneError("only one <sensor> is supported", obj.get("_loc"))
        p = self.props(obj, "sensor")
        to_world = p.transform("to_world")
        fov = p.float("fov", 0.0) if p.has("fov") else None
        if fov is None:
            raise SceneError("the perspective sensor needs 'fov' (focal_length is not supported)", p.loc)
        if not 0 < fov < 180:
            raise SceneError("fov must be in (0, 180) degrees", p.loc)
        fov_axis = p.string("fov_axis", "x")
        if fov_axis not in ("x", "y", "smaller", "larger", "diagonal"):
            raise SceneError(f"unknown fov_axis '{fov_axis}'", p.loc)
        if p.has("near_clip"):
            p.float("near_clip")
        far_clip = p.float("far_clip", 1.0e4)
        aperture, focus = 0.0, far_clip  # Mitsuba 3's focus_distance defaults to far_clip
        if p.type == "thinlens":
            aperture = p.float("aperture_radius")  # required, as in Mitsuba 3
            if aperture < 0:
                raise SceneError("aperture_radius must be non-negative", p._loc_of("aperture_radius"))
            focus = p.float("focus_distance", far_clip)
            if focus <= 0:
                raise SceneError("focus_distance must be positive", p._loc_of("focus_distance"))
        elif p.has("aperture_radius"):  # ignored, it would render a pinhole's image
            raise SceneError("aperture_radius needs a thinlens sensor (this one is perspective: a pinhole)",
                             p._loc_of("aperture_radius"))
        elif p.has("focus_distance"):
            p.float("focus_distance")  # a pinhole's focus distance changes nothing
        width, height, filt = 768, 576, ("gaussian", 2.0, 0.5)
        for child in p.children():
            kind = self.kind_of(child)
            if kind == "film":
                width, height, filt = self.film(child)
            elif kind == "sampler":
                sp = self.props(child, "sampler")
                self.spp = sp.int("sample_count", 4)
                problem = limits.spp_problem(self.spp, "sample_count")
                if problem:
                    raise SceneError(problem, sp.loc)
                if sp.has("seed"):
                    sp.int("seed")
                if sp.type != "independent":
                    warn(f"sampler '{sp.type}' is replaced by independent sampling", sp.loc)
                for k in ("jitter", "scramble_type", "strength"):
                    if sp.has(k):
                        sp.queried.add(k)
                sp.warn_unqueried()
            else:
                raise SceneError(f"a {kind} cannot be nested in a sensor", child.get("_loc"))
        # Mitsuba's camera frame must not scale; strip any scale of the rotation part.
        m = to_world.copy()
        m[:3, :3] /= np.linalg.norm(m[:3, :3], axis=0, keepdims=True)
        self.camera = CameraDesc(m, fov, fov_axis, width, height, *filt, aperture_radius=aperture,
                                 focus_distance=focus)
        p.warn_unqueried()

    def film(self, obj):
        p = self.props(obj, "film")
        w, h = p.int("width", 768), p.int("height", 576)
        problem = limits.film_problem(w, h)
        if problem:
            raise SceneError(problem, p.loc)
        for k in ("file_format", "pixel_format", "component_format"):
            if p.has(k):
                p.string(k)
        for k in ("banner", "sample_border"):
            if p.has(k):
                p.bool(k)
        if p.has("high_quality_edges") and p.bool("high_quality_edges"):
            # Mitsuba 0.6's option (Mitsuba 3 stops on it): samples outside the image for the
            # border pixels' filter; here only a filter radius of border pixels differs
            warn("high_quality_edges (Mitsuba 0.6) is ignored: the border pixels are filtered from samples "
                 "inside the image only", p.loc)
        filt = ("gaussian", 2.0, 0.5)
        for child in p.children():
            fp = self.props(child, "rfilter")
            if fp.type == "box":
                filt = ("box", fp.float("radius", 0.5), 0.5)
            elif fp.type == "tent":
                filt = ("tent", fp.float("radius", 1.0), 0.5)
            else:
                sd = fp.float("stddev", 0.5)
                filt = ("gaussian", 4 * sd, sd)
            if filt[1] <= 0:
                raise SceneError("filter radius must be positive", fp.loc)
            fp.warn_unqueried()
        p.warn_unqueried()
        return w, h, filt

    # --------------------------------------------------------------- materials
    def material(self, obj) -> int:
        key = id(obj)
        if key in self.material_index:
            return self.material_index[key]
        p = self.props(obj, "bsdf")
        if p.type == "mixture":
            return self.mixture(obj, p)
        mask = None
        if p.type == "mask":
            mask, obj = self.mask(p)
            p = self.props(obj, "bsdf")
        bump = None
        if p.type in PERTURBING:
            bump, obj = self.bumpmap(p)
            p = self.props(obj, "bsdf")
        if p.type == "twosided":
            inner = p.children()
            if len(inner) != 1:
                raise SceneError("twosided needs exactly one nested BSDF (two different sides are not supported)", p.loc)
            m = self.material_desc(inner[0])
            m.twosided = True
            p.warn_unqueried()
        else:
            m = self.material_desc(obj)
        m.bump = bump
        if mask is not None:
            m.masked = True
            m.opacity, tex = mask
            if tex is not None:
                m.textures["opacity"] = tex
        self.materials.append(m)
        self.material_index[key] = len(self.materials) - 1
        return self.material_index[key]

    def mixture(self, obj, p: Props) -> int:
        """restir's `mixture` (the pbrt-v4 loader's `mix`): `bsdf_a` and `bsdf_b` and an `amount`
        (a number or a texture, read as a scalar), each surface point taking b with probability
        amount (scene_device.material_index_at)."""
        inner = [p.obj.get("bsdf_a"), p.obj.get("bsdf_b")]
        if not all(isinstance(b, dict) for b in inner):
            raise SceneError("mixture needs the BSDFs 'bsdf_a' and 'bsdf_b'", p.loc)
        p.queried.update(("bsdf_a", "bsdf_b"))
        ids = [self.material(p.resolve(b) if b.get("type") == "ref" else b) for b in inner]
        if any(self.materials[i].mix is not None for i in ids):
            raise SceneError("a mixture of mixtures is not supported", p.loc)
        m = MaterialDesc(kind="mixture", mix=(ids[0], ids[1]))
        v = p.color_or_texture("amount", np.full(3, 0.5))
        if isinstance(v, dict):
            m.textures["amount"] = self.texture(v)
        else:
            if not np.all(v == v[0]):
                raise SceneError("a mixture's amount is one number, not a colour", p._loc_of("amount"))
            m.mix_amount = float(np.clip(v[0], 0.0, 1.0))
        p.warn_unqueried()
        self.materials.append(m)
        self.material_index[id(obj)] = len(self.materials) - 1
        return len(self.materials) - 1

    def bumpmap(self, p: Props) -> tuple[BumpDesc, dict]:
        """Mitsuba 3's `bumpmap` and `normalmap`: exactly one texture (a height map; a normal map,
        its parameter `normalmap`) and one BSDF (which may be a twosided; Bitterli's scenes wrap
        one). Returns the map and the BSDF's object."""
        what = p.type
        kids = p.children()
        textures = [c for c in kids if self.kind_of(c) == "texture"]
        bsdfs = [c for c in kids if self.kind_of(c) == "bsdf"]
        if len(bsdfs) != 1 or len(textures) != 1 or len(kids) != 2:
            map_name = "its height map" if what == "bumpmap" else "'normalmap'"
            raise SceneError(f"{what} needs exactly one nested BSDF and one texture ({map_name})", p.loc)
        tex, inner = textures[0], bsdfs[0]
        if inner.get("type") in PERTURBING:
            raise SceneError("nested bumpmap and normalmap BSDFs are not supported", inner.get("_loc", p.loc))
        if tex.get("type") == "checkerboard":
            reason = "a checkerboard has no gradient" if what == "bumpmap" else "a checkerboard is not a normal map"
            raise SceneError(f"a {what}'s {'height' if what == 'bumpmap' else 'normal'} map must be a bitmap: {reason}",
                             tex.get("_loc", p.loc))
        common = dict(flip_invalid_normals=p.bool("flip_invalid_normals", True),
                      use_shadowing_function=p.bool("use_shadowing_function", True))
        if what == "bumpmap":
            b = BumpDesc(self.texture(tex), scale=p.float("scale", 1.0), **common)
            if self.textures[b.texture].filter == "nearest":
                warn("bumpmap: a height map with filter_type 'nearest' has gradient 0 almost everywhere, so the "
                     "surface renders flat (as in Mitsuba 3)", tex.get("_loc", p.loc))
        else:
            # restir's extensions, for the glTF reader: glTF's normalTexture.scale, and MikkTSpace's
            # bitangent sign on triangles whose uv mapping is mirrored
            b = BumpDesc(self.texture(tex), scale=p.float("strength", 1.0), kind="normal",
                         uv_handed=p.bool("uv_handed", False), **common)
            fname = tex.get("filename")
            if isinstance(fname, str) and not Props(tex, self.ids).bool("raw", False) and \
                    not fname.lower().endswith((".exr", ".hdr", ".pfm")):
                warn(f"normalmap: '{fname}' is read as sRGB-encoded colour, as Mitsuba 3 reads a bitmap without "
                     "raw=true; normal maps are stored linear (add <boolean name=\"raw\" value=\"true\"/>)",
                     tex.get("_loc", p.loc))
        p.warn_unqueried()
        return b, inner

    def mask(self, p: Props) -> tuple[tuple[float, int | None], dict]:
        """Mitsuba 3's `mask`: an opacity (a number, a grey spectrum, or a texture read as its
        luminance, Mitsuba's eval_1; default 0.5) and exactly one BSDF, which may be a bumpmap or
        a twosided. Returns ((constant opacity, texture index or None), the BSDF's object)."""
        kids = p.children()
        bsdfs = [c for c in kids if self.kind_of(c) == "bsdf"]
        if len(bsdfs) != 1 or len(kids) > 2:
            raise SceneError("mask needs exactly one nested BSDF (and an opacity)", p.loc)
        inner = bsdfs[0]
        if inner.get("type") == "mask":
            raise SceneError("nested mask BSDFs are not supported", inner.get("_loc", p.loc))
        v = p.color_or_texture("opacity", np.full(3, 0.5))
        if isinstance(v, dict):
            if self.kind_of(v) != "texture":
                raise SceneError("a mask's opacity must be a number or a texture", p._loc_of("opacity"))
            mask = (1.0, self.texture(v))
            self.warn_dropped_alpha(v)
        else:
            if not np.all(v == v[0]):
                raise SceneError("a mask's opacity is one number (Mitsuba 3 reads a scalar), not a colour",
                                 p._loc_of("opacity"))
            mask = (float(np.clip(v[0], 0.0, 1.0)), None)
        p.warn_unqueried()
        return mask, inner

    def warn_dropped_alpha(self, tex: dict) -> None:
        """A mask's opacity is the bitmap's RGB luminance: Mitsuba 3 drops an alpha channel (its
        bitmap texture keeps Y or RGB), and so does restir. Bitterli's living room masks its
        plant by such a file (leaf.png: RGB near white where alpha is 0), so the leaves come out
        the other way round in both renderers; said, since the file's author meant the alpha."""
        fname = tex.get("filename")
        if tex.get("type") != "bitmap" or not isinstance(fname, str):
            return
        path = fname if os.path.isabs(fname) else os.path.join(self.base_dir, fname)
        try:
            from PIL import Image

            with Image.open(path) as im:
                alpha = im.mode in ("RGBA", "LA", "PA") or "transparency" in im.info
        except Exception:  # not a PIL image (EXR, HDR, PFM), or missing: read as RGB anyway
            return
        if alpha:
            warn(f"mask: '{fname}' has an alpha channel, which is dropped: the opacity is the luminance of "
                 "its RGB, as in Mitsuba 3 (to mask by the alpha, save it as a greyscale image)", tex.get("_loc"))

    def warn_unapplied_bumps(self) -> None:
        """Bitterli's scenes declare `<bsdf type="bumpmap"> ... <bsdf type="twosided" id="X">` and
        let shapes refer to X: the shapes then get X without the bump, in Mitsuba 3 as here (its
        renders, measured: the same image as with no bumpmap at all). Said, since the file's
        author meant a bump."""
        for obj in self.bump_wrappers:
            if id(obj) in self.material_index:
                continue
            for inner in Props(obj, self.ids).children():
                if (inner.get("_kind") or TYPE_TO_KIND.get(inner.get("type"))) == "bsdf" and id(inner) in self.material_index:
                    t = obj.get("type")
                    warn(f"this {t} is not applied: shapes refer to the BSDF '{inner.get('id', '?')}' inside it, "
                         f"not to the {t}, and get it without the {t}, as in Mitsuba 3 (to apply it, "
                         f"give the {t} an id and refer to that)", obj.get("_loc"))

    def ior(self, p: Props, name: str, default: float) -> float:
        if not p.has(name):
            return default
        v = p.obj[name]
        if isinstance(v, str):
            p.queried.add(name)
            if v.lower() not in IOR_TABLE:
                raise SceneError(f"unknown IOR name '{v}'", p.loc)
            return IOR_TABLE[v.lower()]
        return p.float(name)

    def material_desc(self, obj) -> MaterialDesc:
        p = self.props(obj, "bsdf")
        t = p.type
        m = MaterialDesc(kind=t)
        if t == "twosided":
            raise SceneError("nested twosided BSDFs are not supported", p.loc)
        if t in PERTURBING:
            raise SceneError(f"a {t} inside a twosided is not supported: put the twosided inside the {t} "
                             "(as Bitterli's scenes do)", p.loc)
        if t == "mask":
            raise SceneError("a mask must be the outermost BSDF: put the twosided or bumpmap inside the mask "
                             "(as Bitterli's scenes do)", p.loc)
        if t == "diffuse":
            self.spectrum(p, m, "reflectance", "reflectance", np.full(3, 0.5))
        if t == "diffuse_transmission":  # restir's: pbrt-v4's (device/bsdfs/diffuse_transmission.py)
            self.spectrum(p, m, "reflectance", "reflectance", np.full(3, 0.25))
            self.spectrum(p, m, "transmittance", "specular_transmittance", np.full(3, 0.25))
            m.twosided = True  # the same from both sides
        if t == "metallic_roughness":  # restir's: glTF 2.0's material (device/bsdfs/metallic_roughness.py)
            self.spectrum(p, m, "base_color", "reflectance", np.ones(3))
            m.distribution = "ggx"
            for name in ("metallic", "roughness"):
                v = p.color_or_texture(name, np.ones(3))
                if isinstance(v, dict):
                    m.textures[name] = self.texture(v)
                    v = np.ones(3)
                elif not (np.all(v == v[0]) and 0.0 <= v[0] <= 1.0):
                    raise SceneError(f"metallic_roughness: {name} is one number in [0, 1]", p._loc_of(name))
                if name == "metallic":
                    m.metallic = float(v[0])
                else:  # alpha = roughness^2 (glTF's), at least 1e-4 as every microfacet material here
                    m.alpha_u = m.alpha_v = max(float(v[0]) ** 2, 1e-4)
                    m.roughness_remap = 2
        if t in ("conductor", "roughconductor"):
            material = p.string("material", "none")
            if p.has("eta") or material == "none":
                m.eta = p.rgb("eta", np.zeros(3))
                m.k = p.rgb("k", np.ones(3))
            else:
                raise SceneError(f"named conductor material '{material}' is not supported; give eta and k", p.loc)
            self.spectrum(p, m, "specular_reflectance", "specular_reflectance", np.ones(3))
        if t in ("dielectric", "thindielectric", "roughdielectric"):
            int_ior = self.ior(p, "int_ior", 1.5046)
            ext_ior = self.ior(p, "ext_ior", 1.000277)
            if int_ior <= 0 or ext_ior <= 0:
                raise SceneError("IORs must be positive", p.loc)
            m.ior = int_ior / ext_ior
            self.spectrum(p, m, "specular_reflectance", "specular_reflectance", np.ones(3))
            self.spectrum(p, m, "specular_transmittance", "specular_transmittance", np.ones(3))
        if t in ("plastic", "roughplastic"):
            int_ior = self.ior(p, "int_ior", IOR_TABLE["polypropylene"])
            ext_ior = self.ior(p, "ext_ior", IOR_TABLE["air"])
            if int_ior <= 0 or ext_ior <= 0:
                raise SceneError("IORs must be positive", p.loc)
            m.ior = int_ior / ext_ior
            d_mean = self.spectrum(p, m, "diffuse_reflectance", "reflectance", np.full(3, 0.5))
            s_mean = self.spectrum(p, m, "specular_reflectance", "specular_reflectance", np.ones(3))
            m.specular_sampling_weight = s_mean / (d_mean + s_mean)
            m.nonlinear = p.bool("nonlinear", False)
            if t == "plastic":
                m.fdr_int = fresnel_diffuse_reflectance(1.0 / m.ior)
            else:
                from .coat_tables import roughplastic_tables

                m.distribution = p.string("distribution", "beckmann")
                if m.distribution not in ("beckmann", "ggx"):
                    raise SceneError(f"unknown microfacet distribution '{m.distribution}'", p.loc)
                if p.has("alpha_u") or p.has("alpha_v"):
                    raise SceneError("roughplastic supports isotropic roughness only (as Mitsuba)", p.loc)
                m.alpha_u = m.alpha_v = max(p.float("alpha", 0.1), 1e-4)
                if p.has("sample_visible"):
                    p.bool("sample_visible")
                if m.ior == 1.0:
                    raise SceneError("roughplastic needs int_ior != ext_ior", p.loc)
                m.coat_transmittance, m.fdr_int = roughplastic_tables(m.distribution, m.alpha_u, m.ior)
        if t in ("roughconductor", "roughdielectric"):
            m.distribution = p.string("distribution", "beckmann")
            if m.distribution not in ("beckmann", "ggx"):
                raise SceneError(f"unknown microfacet distribution '{m.distribution}'", p.loc)
            alpha = p.color_or_texture("alpha", np.full(3, 0.1)) if p.has("alpha") else None
            if p.has("alpha_u") or p.has("alpha_v"):
                m.alpha_u, m.alpha_v = p.float("alpha_u"), p.float("alpha_v")
            elif isinstance(alpha, dict):  # textured (Mitsuba 3's texturable alpha; pbrt-v4's roughness)
                m.textures["roughness"] = self.texture(alpha)
                m.roughness_remap = 1 if p.bool("remap_roughness", False) else 0
                m.alpha_u = m.alpha_v = 0.1  # replaced at every hit
            else:
                m.alpha_u = m.alpha_v = p.float("alpha", 0.1)
            if min(m.alpha_u, m.alpha_v) <= 0:
                raise SceneError("roughness alpha must be positive", p.loc)
            # Mitsuba clamps alpha from below to avoid numerical trouble (1e-4).
            m.alpha_u, m.alpha_v = max(m.alpha_u, 1e-4), max(m.alpha_v, 1e-4)
            if p.has("sample_visible"):
                p.bool("sample_visible")
        p.warn_unqueried()
        return m

    def spectrum(self, p: Props, m: MaterialDesc, name: str, param: str, default: np.ndarray) -> float:
        """The RGB parameter `name` of the BSDF into the material's `param` (a constant, or a
        texture index that the device resolves at each hit: scene_device.textured_material); returns
        its mean value (of the texture's texels if textured), which sampling weights use."""
        v = p.color_or_texture(name, default)
        if isinstance(v, dict):
            m.textures[param] = self.texture(v)
            setattr(m, param, np.ones(3))
            return self.textures[m.textures[param]].mean()
        if np.any(v < 0):  # no surface reflects a negative amount of light
            raise SceneError(f"parameter '{name}' must be non-negative", p._loc_of(name))
        setattr(m, param, v)
        return float(np.mean(v))

    def texture(self, obj) -> int:
        """A bitmap or checkerboard (scene/textures.py) into the scene's textures; its index."""
        p = self.props(obj, "texture")
        to_uv, dropped = uv_transform(p.transform("to_uv"))
        if dropped:
            warn("'to_uv': the third column of the transform's first two rows is ignored, as Mitsuba 3 "
                 "ignores it (a uv offset is <translate x=.. y=..>)", p._loc_of("to_uv"))
        if p.type == "checkerboard":
            t = TextureDesc("checkerboard", to_uv, color0=p.rgb("color0", np.full(3, 0.4)),
                            color1=p.rgb("color1", np.full(3, 0.2)))
        elif p.has("data"):  # restir extension for other formats' loaders: texels decoded already (linear RGB)
            p.queried.add("data")
            img = np.ascontiguousarray(np.asarray(p.obj["data"], np.float32))
            if img.ndim != 3 or img.shape[2] != 3 or img.shape[0] < 1 or img.shape[1] < 1 or not np.all(np.isfinite(img)):
                raise SceneError("a texture's data must be finite H x W x 3 texels", p.loc)
            t = TextureDesc("bitmap", to_uv, img, filter=self.choice(p, "filter_type", "bilinear", FILTERS),
                            wrap=self.choice(p, "wrap_mode", "repeat", WRAPS))
        else:
            fname = p.string("filename")
            path = fname if os.path.isabs(fname) else os.path.join(self.base_dir, fname)
            raw = p.bool("raw", False)
            if os.path.exists(path):
                img = _read_image(path, fname, p.loc, linearize_srgb=not raw)
                img = self.texel_transform(p, img, path, fname, raw)
            elif self.missing_textures == "grey":
                warn(f"texture file '{fname}' not found: rendered as constant grey {MISSING_GREY} "
                     "(--missing-textures grey); the image is not the scene's", p.loc)
                img = np.full((1, 1, 3), MISSING_GREY, np.float32)
            else:
                raise SceneError(f"texture file '{fname}' not found (--missing-textures grey renders it as grey "
                                 "with a warning)", p.loc)
            t = TextureDesc("bitmap", to_uv, img, filter=self.choice(p, "filter_type", "bilinear", FILTERS),
                            wrap=self.choice(p, "wrap_mode", "repeat", WRAPS))
        p.warn_unqueried()
        self.textures.append(t)
        return len(self.textures) - 1

    @staticmethod
    def texel_transform(p: Props, img: np.ndarray, path: str, fname: str, raw: bool) -> np.ndarray:
        """restir's bitmap extensions for other formats' textures (the pbrt-v4 loader's): `channels`
        "average" (the mean of R, G and B in each channel) or "alpha" (the alpha channel, 1 where
        the file has none), then `texel_scale` and `invert` (1 - value, at least 0), as pbrt-v4
        applies its image textures' scale and invert."""
        channels = p.string("channels", "rgb") if p.has("channels") else "rgb"
        if channels == "average":
            img = np.repeat(img.mean(axis=2, keepdims=True), 3, axis=2)
        elif channels == "alpha":
            from PIL import Image

            try:
                with Image.open(path) as im:
                    has_alpha = im.mode in ("RGBA", "LA", "PA") or "transparency" in im.info
                    a = np.asarray(im.convert("RGBA"))[..., 3].astype(np.float32) / 255.0 if has_alpha else None
            except Exception:  # not a PIL image (EXR, HDR, PFM): no alpha channel read here
                a = None
            img = np.ones_like(img) if a is None else np.repeat(a[..., None], 3, axis=2)
        elif channels != "rgb":
            raise SceneError(f"bitmap: channels '{channels}' is not one of rgb, average, alpha", p._loc_of("channels"))
        if p.has("texel_scale"):
            img = img * np.float32(p.float("texel_scale"))
        if p.has("invert") and p.bool("invert"):
            img = np.maximum(np.float32(1.0) - img, np.float32(0.0))
        return np.ascontiguousarray(img, np.float32)

    @staticmethod
    def choice(p: Props, name: str, default: str, allowed: tuple) -> str:
        v = p.string(name, default)
        if v not in allowed:
            raise SceneError(f"'{p.type}': {name} '{v}' is not supported (one of {', '.join(allowed)})",
                             p._loc_of(name))
        return v

    # --------------------------------------------------------------- shapes and emitters
    def shape(self, obj):
        p = self.props(obj, "shape")
        t = p.type
        to_world = p.transform("to_world")
        linear = to_world[:3, :3]
        if abs(np.linalg.det(linear)) <= 1e-12 * np.prod(np.linalg.norm(linear, axis=0)) or not linear.any():
            # a zero scale (or a rank-deficient matrix) has no inverse for the normals
            raise SceneError("the shape's to_world is singular (a scale of 0 on some axis?): it has no normals",
                             p.loc)
        if t == "sphere":
            center = p.vec3("center", np.zeros(3))
            radius = p.float("radius", 1.0)
            if radius <= 0:
                raise SceneError("sphere radius must be positive", p.loc)
            m = np.diag([radius, radius, radius, 1.0])
            m[:3, 3] = center
            to_world = to_world @ m
            seg = int(p.int("segments", 0)) if p.has("segments") else 0
            mesh = shape_lib.sphere((2 * seg, seg)) if seg else shape_lib.sphere()
        elif t == "rectangle":
            mesh = shape_lib.rectangle()
        elif t == "cube":
            mesh = shape_lib.cube()
        elif t == "disk":
            mesh = shape_lib.disk()
        elif t == "triangles":  # restir extension for other formats' loaders: a mesh in world space, read here
            mesh = p.obj["load"]()
            p.queried.add("load")
        elif t == "trimesh":  # restir extension for builtin scenes: inline vertices and faces
            mesh = shape_lib.TriMesh(np.asarray(p.obj["vertices"], float)[np.asarray(p.obj["faces"])], None,
                                     shape_lib.barycentric_uvs(len(p.obj["faces"])))
            p.queried.update(("vertices", "faces"))

        else:
            fname = p.string("filename")
            path = fname if os.path.isabs(fname) else os.path.join(self.base_dir, fname)
            if not os.path.exists(path):
                raise SceneError(f"mesh file '{fname}' not found", p.loc)
            mesh = shape_lib.load_obj(path, p.loc) if t == "obj" else shape_lib.load_ply(path, p.loc)
        face_normals = p.bool("face_normals", False) if t in ("obj", "ply") else False
        flip = p.bool("flip_normals", False)
        bsdf_obj, emitter_obj = None, None
        for child in p.children():
            kind = self.kind_of(child)
            if kind == "bsdf":
                bsdf_obj = child
            elif kind == "emitter":
                emitter_obj = child
            else:
                raise SceneError(f"a {kind} cannot be nested in a shape", child.get("_loc"))
        if bsdf_obj is None:
            # Mitsuba 3's default: diffuse 0.5, but black on an emitter (checked with its own loader)
            bsdf_obj = {"type": "diffuse", "_kind": "bsdf", "_loc": p.loc}
            if emitter_obj is not None:
                bsdf_obj["reflectance"] = np.zeros(3)
        mat = self.material(bsdf_obj)
        emission = np.zeros(3)
        twosided = False
        if emitter_obj is not None:
            ep = self.props(emitter_obj, "emitter")
            if ep.type != "area":
                raise SceneError(f"a '{ep.type}' emitter cannot be attached to a shape", ep.loc)
            emission = ep.rgb("radiance")
            if np.any(emission < 0):
                raise SceneError("radiance must be non-negative", ep.loc)
            # restir's extension (Mitsuba 3's area emitter is one-sided), for pbrt-v4's `twosided`
            # area lights and glTF's double-sided emissive materials: the radiance leaves both sides
            twosided = ep.bool("twosided", False)
            ep.warn_unqueried()
        pos = transform_points(to_world, mesh.positions.reshape(-1, 3)).reshape(-1, 3, 3)
        nrm = transform_normals(to_world, mesh.normals.reshape(-1, 3)).reshape(-1, 3, 3) if mesh.normals is not None else None
        uvs = mesh.uvs
        tangents = getattr(mesh, "tangents", None)  # (T, 3, 4), from a triangles shape (glTF), already in world space
        analytic = t in ("rectangle", "disk", "sphere", "trimesh")
        if analytic and np.linalg.det(to_world[:3, :3]) < 0:
            # Mitsuba's analytic shapes keep their normal under mirroring transforms.
            pos, nrm, uvs = pos[:, ::-1], nrm[:, ::-1], uvs[:, ::-1]
        if flip:
            pos, uvs = pos[:, ::-1], uvs[:, ::-1]
            nrm = -nrm[:, ::-1] if nrm is not None else None
            if tangents is not None:  # the normal turned: the bitangent keeps its direction by its sign
                tangents = tangents[:, ::-1] * np.array([1.0, 1.0, 1.0, -1.0])
        smooth = 0 if (face_normals or nrm is None or t in ("rectangle", "disk", "trimesh")) else 1
        if nrm is None:
            nrm = np.zeros_like(pos)
        area = 0.5 * np.linalg.norm(np.cross(pos[:, 1] - pos[:, 0], pos[:, 2] - pos[:, 0]), axis=1)
        keep = area > 0
        pos, nrm, uvs = pos[keep], nrm[keep], uvs[keep]
        tangents = tangents[keep] if tangents is not None else None
        if mesh.emission is not None and emitter_obj is not None:  # per-triangle radiance (a triangles shape's)
            emission = np.asarray(mesh.emission, np.float64)[keep]
        p.warn_unqueried()
        if len(pos):
            self.parts.append((pos, nrm, uvs, smooth, mat, emission, twosided and bool(np.any(emission > 0)),
                               tangents))
        else:  # legal (Mitsuba renders it as nothing) but surely not what was meant
            what = "an emitter" if np.any(emission > 0) else "a shape"
            warn(f"{what} whose every triangle has zero area: it is left out of the image", p.loc)

    def delta_light(self, obj) -> DeltaLightDesc:
        """Mitsuba 3's point, spot and directional emitters."""
        p = self.props(obj, "emitter")
        t = p.type
        name = "irradiance" if t == "directional" else "intensity"
        value = p.rgb(name, np.ones(3))
        if np.any(value < 0):
            raise SceneError(f"{name} must be non-negative", p._loc_of(name))
        where = "direction" if t == "directional" else "position"
        if t != "spot" and p.has(where) and p.has("to_world"):
            raise SceneError(f"give a {t} emitter '{where}' or 'to_world', not both", p.loc)
        m = p.transform("to_world")
        if t == "point":
            pos = p.vec3("position") if p.has("position") else m[:3, 3]
            light = DeltaLightDesc("point", value, position=np.asarray(pos, float))
        elif t == "directional":
            axis = p.vec3("direction") if p.has("direction") else m[:3, :3] @ np.array([0.0, 0.0, 1.0])
            if np.linalg.norm(axis) <= 0:
                raise SceneError("the directional emitter's direction is zero", p.loc)
            light = DeltaLightDesc("directional", value, axis=axis / np.linalg.norm(axis))
        else:
            for wrong in ("position", "direction"):
                if p.has(wrong):  # ignored, it would leave the spot at the origin, shining along +z
                    raise SceneError(f"a spot emitter is placed and aimed by 'to_world' (Mitsuba 3 has no '{wrong}' "
                                     "for it)", p._loc_of(wrong))
            if p.has("texture"):
                raise SceneError("a spot emitter's 'texture' (a projected image) is not supported", p._loc_of("texture"))
            axis = m[:3, :3] @ np.array([0.0, 0.0, 1.0])
            if np.linalg.norm(axis) <= 0:
                raise SceneError("the spot emitter's to_world maps its axis to zero", p.loc)
            cutoff = p.float("cutoff_angle", 20.0)
            beam = p.float("beam_width", cutoff * 0.75)
            if not 0 < cutoff <= 180:
                raise SceneError("cutoff_angle must be in (0, 180] degrees", p._loc_of("cutoff_angle"))
            if not 0 <= beam <= cutoff:
                raise SceneError("beam_width must be in [0, cutoff_angle] degrees", p._loc_of("beam_width"))
            # `falloff`: restir's extension for other formats' spots (scene/delta_lights.py)
            falloff = self.choice(p, "falloff", "linear_angle", FALLOFFS) if p.has("falloff") else "linear_angle"
            light = DeltaLightDesc("spot", value, position=m[:3, 3].astype(float), axis=axis / np.linalg.norm(axis),
                                   falloff=falloff, inner=math.radians(beam), outer=math.radians(cutoff))
        p.warn_unqueried()
        return light

    def environment(self, obj):
        p = self.props(obj, "emitter")
        if p.type == "area":
            raise SceneError("an area emitter must be nested in a shape", p.loc)
        if self.env is not None:
            raise SceneError("only one environment emitter is supported", p.loc)
        rot = p.transform("to_world")[:3, :3]
        if p.type == "constant":
            radiance = p.rgb("radiance", np.ones(3))
            if np.any(radiance < 0):
                raise SceneError("radiance must be non-negative", p._loc_of("radiance"))
            self.env = ("constant", radiance, rot, None)
        else:
            if p.has("data"):  # restir extension for other formats' loaders: the map decoded already
                p.queried.add("data")
                img, fname = np.ascontiguousarray(np.asarray(p.obj["data"], np.float32)), "(data)"
            else:
                fname = p.string("filename")
                path = fname if os.path.isabs(fname) else os.path.join(self.base_dir, fname)
                if not os.path.exists(path):
                    raise SceneError(f"environment map '{fname}' not found", p.loc)
                img = _read_image(path, fname, p.loc, linearize_srgb=True)
            if img.shape[0] < 3 or img.shape[1] < 2:
                raise SceneError(f"environment map '{fname}' must be at least 2x3 pixels", p.loc)
            scale = p.float("scale", 1.0)
            if scale < 0:
                raise SceneError("scale must be non-negative", p._loc_of("scale"))
            self.env = ("envmap", np.full(3, scale), rot, img)
        p.warn_unqueried()


def _read_image(path: str, fname: str, loc: str, linearize_srgb: bool) -> np.ndarray:
    from ..image_io import read_image

    try:
        img = read_image(path, linearize_srgb=linearize_srgb)
    except Exception as e:  # image libraries raise many exception types for unreadable files
        raise SceneError(f"cannot read image '{fname}': {e}", loc) from None
    if not np.all(np.isfinite(img)):
        raise SceneError(f"image '{fname}' contains NaN or inf", loc)
    return img


def build_scene(tree: dict, name: str = "scene", missing_textures: str = "error", progress=None) -> Scene:
    """Build a host Scene from a Mitsuba-style scene dict; `missing_textures` (MISSING_TEXTURES)
    says what a bitmap whose file is missing becomes: an error, or constant grey with a warning.
    `progress(done, total)`, when given, is called before each top-level element (shapes, the
    sensor, emitters) and once at the end: meshes are read there, most of a large scene's load.
    A tree's "_animation" (scene/animation.py Animation: a builtin's, a glTF file's) animates the
    scene."""
    scene = _Builder(tree, name, missing_textures, progress).build()
    if tree.get("_animation") is not None:
        from .animation import animate

        a = tree["_animation"]
        scene = animate(scene, a.motions, a.callback, a.frames)
    return scene
