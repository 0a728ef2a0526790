"""pbrt-v4's materials and textures as restir's (Mitsuba-style) BSDF and texture objects.

Every pbrt-v4 material reflects on both sides except the dielectrics, which are interfaces, so
reflecting ones are wrapped in `twosided`. Roughness: pbrt-v4's Trowbridge-Reitz (GGX) alpha is
sqrt(roughness) when `remaproughness` is true (its default), else the roughness itself; a
surface with alpha below 1e-3 is smooth (pbrt-v4's threshold). `coateddiffuse` (pbrt-v4's
stochastic layered BSDF) is rendered as Mitsuba's `roughplastic` (`plastic` when smooth) with
nonlinear colour, with a warning per material; docs/guide/pbrt.md states how they differ.
"""
import os

import numpy as np

from ..errors import SceneError, warn
from . import spectra
from .params import ParamSet

MATERIALS = ("diffuse", "conductor", "dielectric", "thindielectric", "coateddiffuse", "diffusetransmission", "mix",
             "interface")
NOT_YET = ("coatedconductor", "measured", "hair", "subsurface")
TEXTURES = ("imagemap", "checkerboard", "constant", "scale", "mix")
SMOOTH_ALPHA = 1e-3


class Texture:
    """A `Texture` directive, kept until a material uses it (its type is 'spectrum' or 'float')."""

    def __init__(self, name: str, type_: str, cls: str, ps: ParamSet, base_dir: str):
        self.name, self.type, self.cls, self.ps, self.base_dir = name, type_, cls, ps, base_dir


class Materials:
    """Translates materials and textures; results are cached so that shapes sharing a material share
    one object (the builder makes one material of it)."""

    def __init__(self):
        self.textures: dict[str, Texture] = {}
        self.cache: dict = {}
        self.warned: set = set()

    # ------------------------------------------------------------------ textures
    def define_texture(self, tex: Texture) -> None:
        if tex.type not in ("spectrum", "float"):
            raise SceneError(f"Texture '{tex.name}': type '{tex.type}' is not 'spectrum' or 'float'", tex.ps.loc)
        if tex.cls not in TEXTURES:
            raise SceneError(f"Texture '{tex.name}': class '{tex.cls}' is not supported (supported: "
                             f"{', '.join(TEXTURES)})", tex.ps.loc)
        self.textures[tex.name] = tex

    def value(self, ps: ParamSet, name: str, default, kind: str):
        """A texturable parameter: an RGB array (constant) or a bitmap/checkerboard dict.
        kind: 'spectrum' (a reflectance) or 'float' (read as a grey RGB)."""
        tname = ps.texture(name)
        if tname is not None:
            return self.texture(tname, kind, ps.loc_of(name))
        if not ps.has(name):
            return None if default is None else np.asarray(default, float)
        if ps.type_of(name) == "float":
            return np.full(3, ps.float(name))
        return spectra.reflectance(ps.spectrum(name), ps.loc_of(name))

    def texture(self, tname: str, kind: str, loc: str):
        if tname not in self.textures:
            raise SceneError(f"unknown texture '{tname}'", loc)
        key = ("tex", tname, kind)
        if key not in self.cache:
            self.cache[key] = self._texture(self.textures[tname], kind)
        return self.cache[key]

    def _texture(self, tex: Texture, kind: str):
        ps, loc = tex.ps, tex.ps.loc
        if tex.cls == "constant":
            v = self.value(ps, "value", [1.0, 1.0, 1.0], kind)
            ps.warn_unused()
            return v
        if tex.cls in ("scale", "mix"):
            return self._combination(tex, kind)
        to_uv = self._mapping(ps, checker=tex.cls == "checkerboard")
        if tex.cls == "checkerboard":
            if ps.int("dimension", 2) != 2:
                raise SceneError("checkerboard: only 'dimension' 2 is supported", ps.loc_of("dimension"))
            colors = []
            for t, default in (("tex1", 1.0), ("tex2", 0.0)):
                v = self.value(ps, t, [default] * 3, kind)
                if isinstance(v, dict):
                    raise SceneError(f"checkerboard: a textured '{t}' is not supported (give a value)", ps.loc_of(t))
                colors.append(v)
            ps.warn_unused()
            # pbrt-v4: tex1 where floor(s) + floor(t) is even (texture.py's mapping matches the parity)
            return {"type": "checkerboard", "color0": colors[0], "color1": colors[1], "to_uv": to_uv, "_loc": loc}
        # imagemap
        fname = ps.string("filename")
        if fname is None:
            raise SceneError("imagemap needs 'string filename'", loc)
        path = fname if os.path.isabs(fname) else os.path.join(tex.base_dir, fname)
        filt = ps.string("filter", "bilinear")
        if filt not in ("bilinear", "trilinear", "ewa", "point"):
            raise SceneError(f"imagemap: unknown filter '{filt}'", ps.loc_of("filter"))
        if filt in ("trilinear", "ewa") and ("filter", filt) not in self.warned:
            self.warned.add(("filter", filt))
            warn(f"imagemap: filter '{filt}' is rendered as bilinear (restir has no MIP maps)", ps.loc_of("filter"))
        wrap = ps.string("wrap", "repeat")
        if wrap not in ("repeat", "clamp"):
            raise SceneError(f"imagemap: wrap '{wrap}' is not supported (repeat or clamp)", ps.loc_of("wrap"))
        encoding = ps.string("encoding", None)
        if encoding not in (None, "sRGB", "linear"):
            raise SceneError(f"imagemap: encoding '{encoding}' is not supported (sRGB or linear)", ps.loc_of("encoding"))
        ps.ignore("maxanisotropy")
        d = {"type": "bitmap", "filename": fname, "filter_type": "nearest" if filt == "point" else "bilinear",
             "wrap_mode": wrap, "raw": encoding == "linear", "to_uv": to_uv, "_loc": loc}
        if ps.has("scale"):
            d["texel_scale"] = ps.float("scale")
        if ps.bool("invert", False):
            d["invert"] = True
        if kind == "float":
            d["channels"] = "alpha" if _has_alpha(path) else "average"
        ps.warn_unused()
        return d

    def _combination(self, tex: Texture, kind: str):
        ps = tex.ps
        if tex.cls == "scale":
            a, b = self.value(ps, "tex", [1.0] * 3, kind), self.value(ps, "scale", [1.0] * 3, "float")
            ps.warn_unused()
            if not isinstance(a, dict) and not isinstance(b, dict):
                return a * b
            img, c = (a, b) if isinstance(a, dict) else (b, a)
            if not isinstance(c, dict) and np.all(c == c[0]) and img["type"] == "bitmap" and "invert" not in img:
                out = dict(img)
                out["texel_scale"] = out.get("texel_scale", 1.0) * float(c[0])
                return out
            raise SceneError("scale: only a constant (grey) scale of an image texture is supported", ps.loc)
        a, b = self.value(ps, "tex1", [0.0] * 3, kind), self.value(ps, "tex2", [1.0] * 3, kind)
        amount = self.value(ps, "amount", [0.5] * 3, "float")
        ps.warn_unused()
        if any(isinstance(x, dict) for x in (a, b, amount)):
            raise SceneError("mix: only a mix of constants is supported (textured inputs are not)", ps.loc)
        return (1.0 - amount) * a + amount * b

    @staticmethod
    def _mapping(ps: ParamSet, checker: bool) -> np.ndarray:
        """pbrt-v4's uv mapping (s = su u + du, t = sv v + dv) as a restir to_uv on the stored
        (u, 1 - v) coordinates (shapes.py): images look up (s, 1 - t); a checkerboard's unit checks
        are restir's half-unit ones, so it is mapped to (s / 2, t / 2)."""
        mapping = ps.string("mapping", "uv")
        if mapping != "uv":
            raise SceneError(f"texture mapping '{mapping}' is not supported (uv only)", ps.loc_of("mapping"))
        su, sv = ps.float("uscale", 1.0), ps.float("vscale", 1.0)
        du, dv = ps.float("udelta", 0.0), ps.float("vdelta", 0.0)
        m = np.eye(4)
        if checker:  # t = sv (1 - v') + dv, halved
            m[0, 0], m[0, 3] = su / 2, du / 2
            m[1, 1], m[1, 3] = -sv / 2, (sv + dv) / 2
        else:        # 1 - t = sv v' + 1 - sv - dv
            m[0, 0], m[0, 3] = su, du
            m[1, 1], m[1, 3] = sv, 1.0 - sv - dv
        return m

    # ------------------------------------------------------------------ materials
    def material(self, kind: str, ps: ParamSet, key, named=None) -> dict | None:
        """The BSDF object of a material (None for `interface`: the shape is left out). `named`
        resolves a `mix`'s material names: name -> its BSDF object."""
        if key is not None and ("mat", key) in self.cache:
            return self.cache[("mat", key)]
        if kind == "mix":
            m = self._mix(ps, named)
        else:
            m = self._material(kind, ps)
        if key is not None:
            self.cache[("mat", key)] = m
        return m

    def _material(self, kind: str, ps: ParamSet) -> dict | None:
        loc = ps.loc
        if kind in NOT_YET:
            raise SceneError(f"material '{kind}' is not supported yet (supported: {', '.join(MATERIALS)})", loc)
        if kind not in MATERIALS:
            raise SceneError(f"unknown material '{kind}' (supported: {', '.join(MATERIALS)})", loc)
        normal_map = ps.string("normalmap", None)
        bump = ps.texture("displacement")
        if bump is None and ps.has("displacement"):
            ps.float("displacement")  # a constant displacement moves nothing
        if normal_map is not None and bump is not None:
            warn("the material's 'displacement' is not applied: pbrt-v4 applies only the normal map when a "
                 "material has both", ps.loc_of("displacement"))
            bump = None
        if (normal_map is not None or bump is not None) and "perturbed" not in self.warned:
            self.warned.add("perturbed")
            warn("normal and bump maps are rendered as Mitsuba 3's normalmap and bumpmap, which keep the tilted "
                 "normal on the incoming direction's side and shade the terminator (Estevez et al.); pbrt-v4 does "
                 "neither, so strongly tilted normals shade differently", ps.loc)
        if kind == "interface":
            ps.warn_unused()
            return None
        if kind == "diffuse":
            b = {"type": "diffuse", "reflectance": self.value(ps, "reflectance", [0.5] * 3, "spectrum")}
            b = {"type": "twosided", "bsdf": b}
        elif kind == "conductor":
            b = self._conductor(ps)
        elif kind in ("dielectric", "thindielectric"):
            eta = self._eta(ps)
            if kind == "thindielectric":
                b = {"type": "thindielectric", "int_ior": eta, "ext_ior": 1.0}
            elif (textured := self._textured_alpha(ps)) is not None:
                b = {"type": "roughdielectric", "int_ior": eta, "ext_ior": 1.0, "distribution": "ggx",
                     "alpha": textured[0], "remap_roughness": textured[1]}
            else:
                alpha = self._alpha(ps)
                if alpha is None:
                    b = {"type": "dielectric", "int_ior": eta, "ext_ior": 1.0}
                else:
                    b = {"type": "roughdielectric", "int_ior": eta, "ext_ior": 1.0, "distribution": "ggx",
                         "alpha_u": alpha[0], "alpha_v": alpha[1]}
        elif kind == "diffusetransmission":
            scale = ps.float("scale", 1.0)
            if scale < 0:
                raise SceneError("diffusetransmission: scale must be non-negative", ps.loc_of("scale"))
            b = {"type": "diffuse_transmission",
                 "reflectance": _scaled(self.value(ps, "reflectance", [0.25] * 3, "spectrum"), scale, ps),
                 "transmittance": _scaled(self.value(ps, "transmittance", [0.25] * 3, "spectrum"), scale, ps)}
        else:  # coateddiffuse
            b = self._coateddiffuse(ps)
        if normal_map is not None:  # pbrt-v4 reads it linear, repeated, bilinear, at (u, 1 - v) as its images
            b = {"type": "normalmap", "normalmap": {"type": "bitmap", "filename": normal_map, "raw": True,
                                                    "wrap_mode": "repeat", "filter_type": "bilinear",
                                                    "_loc": ps.loc_of("normalmap")}, "bsdf": b}
        elif bump is not None:
            b = {"type": "bumpmap", "texture": self.texture(bump, "float", ps.loc_of("displacement")), "bsdf": b}
        for d in _walk(b):
            d.setdefault("_loc", loc)
        ps.warn_unused()
        return b

    def _mix(self, ps: ParamSet, named) -> dict:
        """pbrt-v4's `mix`: each surface point takes the second material with probability
        `amount`, which restir's `mixture` does (scene_device.material_index_at)."""
        names = ps.strings("materials")
        if names is None or len(names) != 2:
            raise SceneError("mix needs 'string materials' with two material names", ps.loc)
        bsdfs = [named(n, ps.loc_of("materials")) for n in names]
        if any(b is None for b in bsdfs):
            raise SceneError("mix: an 'interface' material cannot be mixed", ps.loc_of("materials"))
        amount = self.value(ps, "amount", [0.5] * 3, "float")
        ps.warn_unused()
        return {"type": "mixture", "bsdf_a": bsdfs[0], "bsdf_b": bsdfs[1], "amount": amount, "_loc": ps.loc}

    def _textured_alpha(self, ps: ParamSet):
        """A textured `roughness` as restir's textured alpha (None when not textured)."""
        for n in ("uroughness", "vroughness"):
            if ps.texture(n) is not None:
                raise SceneError(f"a textured '{n}' is not supported (a textured 'roughness' is)", ps.loc_of(n))
        tname = ps.texture("roughness")
        if tname is None:
            return None
        if ps.has("uroughness") or ps.has("vroughness"):
            raise SceneError("a textured 'roughness' with 'uroughness' or 'vroughness' is not supported", ps.loc)
        return self.texture(tname, "float", ps.loc_of("roughness")), ps.bool("remaproughness", True)

    def _alpha(self, ps: ParamSet, isotropic: bool = False):
        """(alpha_u, alpha_v) of pbrt-v4's roughness parameters, None when smooth."""
        for n in ("roughness", "uroughness", "vroughness"):
            if ps.texture(n) is not None:
                raise SceneError(f"a textured '{n}' is not supported here (give a number)", ps.loc_of(n))
        r = ps.float("roughness", 0.0)
        ru, rv = ps.float("uroughness", r), ps.float("vroughness", r)
        if min(ru, rv) < 0:
            raise SceneError("roughness must be non-negative", ps.loc)
        remap = ps.bool("remaproughness", True)
        au, av = (np.sqrt(ru), np.sqrt(rv)) if remap else (ru, rv)
        if max(au, av) < SMOOTH_ALPHA:
            return None
        if isotropic and au != av:
            raise SceneError("coateddiffuse: anisotropic roughness is not supported (uroughness = vroughness)", ps.loc)
        return float(max(au, 1e-4)), float(max(av, 1e-4))

    def _eta(self, ps: ParamSet) -> float:
        if ps.texture("eta") is not None:
            raise SceneError("a textured 'eta' is not supported", ps.loc_of("eta"))
        if not ps.has("eta"):
            return 1.5
        if ps.type_of("eta") == "float":
            eta = ps.float("eta")
        else:
            eta = spectra.dielectric_eta(ps.spectrum("eta"), ps.loc_of("eta"))
        if eta <= 0:
            raise SceneError("eta must be positive", ps.loc_of("eta"))
        return eta

    def _conductor(self, ps: ParamSet) -> dict:
        for n in ("eta", "k", "reflectance"):
            if ps.texture(n) is not None:
                raise SceneError(f"conductor: a textured '{n}' is not supported", ps.loc_of(n))
        if ps.has("reflectance"):
            r = spectra.reflectance(ps.spectrum("reflectance"), ps.loc_of("reflectance"))
            if np.any(r < 0) or np.any(r >= 1):
                raise SceneError("conductor: reflectance must be in [0, 1)", ps.loc_of("reflectance"))
            # pbrt-v4: eta = 1 and k = 2 sqrt(r) / sqrt(1 - r), whose normal reflectance is r
            eta, k = np.ones(3), 2.0 * np.sqrt(r) / np.sqrt(1.0 - r)
        else:
            eta_s = ps.spectrum("eta") if ps.has("eta") else ("named", "metal-Cu-eta")
            k_s = ps.spectrum("k") if ps.has("k") else ("named", "metal-Cu-k")
            eta, k = spectra.conductor(eta_s, k_s, ps.loc_of("eta"), ps.loc_of("k"))
        textured = self._textured_alpha(ps)
        alpha = None if textured else self._alpha(ps)
        if textured:
            b = {"type": "roughconductor", "distribution": "ggx", "alpha": textured[0], "remap_roughness": textured[1],
                 "eta": eta, "k": k}
        elif alpha is None:
            b = {"type": "conductor", "eta": eta, "k": k}
        else:
            b = {"type": "roughconductor", "distribution": "ggx", "alpha_u": alpha[0], "alpha_v": alpha[1],
                 "eta": eta, "k": k}
        return {"type": "twosided", "bsdf": b}

    def _coateddiffuse(self, ps: ParamSet) -> dict:
        albedo = self.value(ps, "albedo", None, "spectrum")
        if albedo is not None and (isinstance(albedo, dict) or np.any(albedo != 0)):
            raise SceneError("coateddiffuse: a scattering layer ('albedo' > 0) is not supported", ps.loc_of("albedo"))
        ps.ignore("g", "maxdepth", "nsamples", "thickness")
        eta = self._eta(ps)
        alpha = self._alpha(ps, isotropic=True)
        refl = self.value(ps, "reflectance", [0.5] * 3, "spectrum")
        # once per material: each is translated once (Materials.material's cache)
        warn("coateddiffuse (pbrt-v4's stochastic layered BSDF) is rendered as a "
             f"{'rough ' if alpha else ''}plastic (a {'GGX' if alpha else 'smooth'} dielectric coat of IOR "
             f"{eta:g} over a diffuse base, Mitsuba's model); docs/guide/pbrt.md gives the difference", ps.loc)
        b = {"type": "roughplastic" if alpha else "plastic", "int_ior": eta, "ext_ior": 1.0,
             "diffuse_reflectance": refl, "nonlinear": True}
        if alpha:
            b.update(distribution="ggx", alpha=alpha[0])
        return {"type": "twosided", "bsdf": b}


def _scaled(v, scale: float, ps: ParamSet):
    """A constant or an image texture times `scale` (pbrt-v4's diffusetransmission scale)."""
    if scale == 1.0:
        return v
    if not isinstance(v, dict):
        return v * scale
    if v["type"] != "bitmap":
        raise SceneError("diffusetransmission: a scale with a checkerboard is not supported", ps.loc_of("scale"))
    return {**v, "texel_scale": v.get("texel_scale", 1.0) * scale}


def mask(material: dict, opacity) -> dict:
    """pbrt-v4's shape `alpha`: the surface is there with probability alpha (a stochastic alpha
    test), which is Mitsuba 3's `mask` with that opacity."""
    return {"type": "mask", "opacity": opacity, "bsdf": material, "_loc": material.get("_loc")}


def _walk(d: dict):
    yield d
    for v in d.values():
        if isinstance(v, dict) and "type" in v and v.get("type") not in ("bitmap", "checkerboard"):
            yield from _walk(v)


def _has_alpha(path: str) -> bool:
    try:
        from PIL import Image

        with Image.open(path) as im:
            return im.mode in ("RGBA", "LA", "PA") or "transparency" in im.info
    except Exception:  # a missing file (the builder says so) or not a PIL image (EXR, PFM, HDR)
        return False
