"""glTF 2.0 materials as restir's: the metallic-roughness model (device/bsdfs/metallic_roughness.py)
with its textures, its normal map, `doubleSided`, `alphaMode`, KHR_materials_emissive_strength,
KHR_texture_transform, and KHR_materials_transmission with KHR_materials_ior as a dielectric
mixed in by the transmission factor (docs/guide/gltf.md).

Texture channels as the specification assigns them: base colour RGB (sRGB-encoded) and alpha,
metallic in B and roughness in G of the metallic-roughness texture (linear), emissive RGB (sRGB).
"""
import math

import numpy as np

from ...image_io import srgb_to_linear
from ..errors import SceneError, warn
from .accessors import Buffers

WRAPS = {10497: "repeat", 33648: "mirror", 33071: "clamp"}
NEAREST = (9728, 9984, 9986)  # NEAREST, NEAREST_MIPMAP_NEAREST, NEAREST_MIPMAP_LINEAR


class Materials:
    def __init__(self, gltf, buffers: Buffers, path: str):
        self.gltf, self.buffers, self.path = gltf, buffers, path
        self.images: dict[int, np.ndarray] = {}
        self.cache: dict = {}
        self.warned: set = set()

    def warn_once(self, key, message: str) -> None:
        if key not in self.warned:
            self.warned.add(key)
            warn(message, self.path)

    # ------------------------------------------------------------------ textures
    def texels(self, info, what: str) -> tuple[np.ndarray, dict]:
        """A textureInfo's image (H, W, 4, not linearized) and its sampling (to_uv, filter, wrap)."""
        texs = self.gltf.textures or []
        if not 0 <= info.index < len(texs):
            raise SceneError(f"{what}: texture {info.index} does not exist", self.path)
        tex = texs[info.index]
        if tex.source is None:
            raise SceneError(f"{what}: texture {info.index} has no image (an extension's image format?)", self.path)
        if tex.source not in self.images:
            self.images[tex.source] = self.buffers.image(tex.source)
        tex_coord = info.texCoord or 0
        to_uv = np.eye(4)
        ext = (info.extensions or {}).get("KHR_texture_transform")
        if ext:
            off = ext.get("offset", [0.0, 0.0])
            rot = ext.get("rotation", 0.0)
            sc = ext.get("scale", [1.0, 1.0])
            tex_coord = ext.get("texCoord", tex_coord)
            c, s = math.cos(rot), math.sin(rot)
            # uv' = T(offset) R(rotation) S(scale) uv, R = [[c, s], [-s, c]] (the extension's)
            m = np.array([[c, s], [-s, c]]) @ np.diag(sc)
            to_uv[:2, :2] = m
            to_uv[:2, 3] = off
        if tex_coord != 0:
            raise SceneError(f"{what}: texCoord {tex_coord} (only TEXCOORD_0 is read)", self.path)
        filt, wrap = "bilinear", "repeat"
        if tex.sampler is not None:
            smp = (self.gltf.samplers or [])[tex.sampler]
            if smp.magFilter in NEAREST:
                filt = "nearest"
            ws, wt = WRAPS.get(smp.wrapS or 10497, "repeat"), WRAPS.get(smp.wrapT or 10497, "repeat")
            if ws != wt:
                self.warn_once(("wrap", tex.sampler), f"sampler {tex.sampler}: wrapS and wrapT differ; both use "
                               f"wrapS ({ws})")
            wrap = ws
        return self.images[tex.source], {"to_uv": to_uv, "filter_type": filt, "wrap_mode": wrap}

    @staticmethod
    def bitmap(data: np.ndarray, sampling: dict) -> dict:
        return {"type": "bitmap", "data": np.ascontiguousarray(data, np.float32), **sampling}

    def _normal_mapped(self, b: dict, info, what: str) -> dict:
        """`b` under glTF's tangent-space normal map (linear RGB, its `scale` on x and y), with the
        bitangent's sign taken from each triangle's uv mapping as MikkTSpace takes it (restir's
        `uv_handed`); a mixture's two BSDFs each under it (a normalmap wraps one BSDF)."""
        if b["type"] == "mixture":
            return {**b, "bsdf_a": self._normal_mapped(b["bsdf_a"], info, what),
                    "bsdf_b": self._normal_mapped(b["bsdf_b"], info, what)}
        img, smp = self.texels(info, f"{what}: normalTexture")
        scale = float(info.scale if info.scale is not None else 1.0)
        return {"type": "normalmap", "normalmap": self.bitmap(img[..., :3], smp), "strength": scale,
                "uv_handed": True, "bsdf": b}

    # ------------------------------------------------------------------ materials
    def _of(self, index: int | None):
        mats = self.gltf.materials or []
        return mats[index] if index is not None and 0 <= index < len(mats) else None

    def double_sided(self, index: int | None) -> bool:
        m = self._of(index)
        return bool(m is not None and m.doubleSided)

    def normal_mapped(self, index: int | None) -> bool:
        m = self._of(index)
        return m is not None and m.normalTexture is not None

    def material(self, index: int | None) -> tuple[dict, np.ndarray, dict | None]:
        """(BSDF object, emitted radiance RGB, emissive bitmap or None) of material `index`
        (None: the specification's default material)."""
        if index in self.cache:
            return self.cache[index]
        mats = self.gltf.materials or []
        if index is None:
            out = ({"type": "metallic_roughness", "base_color": np.ones(3), "metallic": np.ones(3),
                    "roughness": np.ones(3)}, np.zeros(3), None)
        elif not 0 <= index < len(mats):
            raise SceneError(f"material {index} does not exist", self.path)
        else:
            out = self._material(index, mats[index])
        self.cache[index] = out
        return out

    def _material(self, i: int, m) -> tuple:
        what = f"material {i} ('{m.name}')" if m.name else f"material {i}"
        pbr = m.pbrMetallicRoughness
        base = np.array((pbr.baseColorFactor if pbr and pbr.baseColorFactor else [1, 1, 1, 1]), float)
        metallic = pbr.metallicFactor if pbr and pbr.metallicFactor is not None else 1.0
        roughness = pbr.roughnessFactor if pbr and pbr.roughnessFactor is not None else 1.0
        b = {"type": "metallic_roughness", "base_color": base[:3], "metallic": np.full(3, metallic),
             "roughness": np.full(3, roughness)}
        alpha_tex = None
        if pbr and pbr.baseColorTexture is not None:
            img, smp = self.texels(pbr.baseColorTexture, f"{what}: baseColorTexture")
            b["base_color"] = self.bitmap(srgb_to_linear(img[..., :3]) * base[:3], smp)
            alpha_tex = (img[..., 3] * base[3], smp)
        if pbr and pbr.metallicRoughnessTexture is not None:
            img, smp = self.texels(pbr.metallicRoughnessTexture, f"{what}: metallicRoughnessTexture")
            b["metallic"] = self.bitmap(np.repeat(img[..., 2:3] * metallic, 3, axis=2), smp)
            b["roughness"] = self.bitmap(np.repeat(img[..., 1:2] * roughness, 3, axis=2), smp)
        if m.occlusionTexture is not None:
            self.warn_once(("occlusion", i), f"{what}: occlusionTexture is not used (a path tracer computes the "
                           "occlusion itself)")
        ext = m.extensions or {}
        transmission = ext.get("KHR_materials_transmission", {})
        t = float(transmission.get("transmissionFactor", 0.0))
        if transmission.get("transmissionTexture") is not None:
            raise SceneError(f"{what}: a transmissionTexture is not supported", self.path)
        if t > 0:
            ior = float(ext.get("KHR_materials_ior", {}).get("ior", 1.5))
            if ior < 1:
                raise SceneError(f"{what}: KHR_materials_ior ior must be at least 1", self.path)
            if isinstance(b["roughness"], dict):
                raise SceneError(f"{what}: transmission with a textured roughness is not supported", self.path)
            alpha = max(roughness * roughness, 1e-4)
            if ior == 1.0:
                glass = {"type": "thindielectric", "int_ior": 1.0, "ext_ior": 1.0}
            elif roughness * roughness < 1e-3:
                glass = {"type": "dielectric", "int_ior": ior, "ext_ior": 1.0}
            else:
                glass = {"type": "roughdielectric", "int_ior": ior, "ext_ior": 1.0, "distribution": "ggx",
                         "alpha": alpha}
            glass["specular_transmittance"] = b["base_color"]
            b = glass if t >= 1.0 else {"type": "mixture", "bsdf_a": b, "bsdf_b": glass, "amount": np.full(3, t)}
        elif m.doubleSided:
            b = {"type": "twosided", "bsdf": b}
        if m.normalTexture is not None:
            b = self._normal_mapped(b, m.normalTexture, what)
        mode = m.alphaMode or "OPAQUE"
        if mode != "OPAQUE":
            opacity = float(base[3])
            if mode == "MASK":
                cutoff = m.alphaCutoff if m.alphaCutoff is not None else 0.5
                if alpha_tex is not None:
                    mask = (alpha_tex[0] >= cutoff).astype(np.float32)
                    opacity = self.bitmap(np.repeat(mask[..., None], 3, axis=2),
                                          {**alpha_tex[1], "filter_type": "nearest"})
                else:
                    opacity = 1.0 if opacity >= cutoff else 0.0
            else:  # BLEND: the coverage alpha as a stochastic opacity
                self.warn_once(("blend", i), f"{what}: alphaMode BLEND is rendered as a mask of opacity alpha (light "
                               "passes straight through with probability 1 - alpha; no refraction or tint)")
                if alpha_tex is not None:
                    opacity = self.bitmap(np.repeat(alpha_tex[0][..., None], 3, axis=2), alpha_tex[1])
            if isinstance(opacity, dict) or opacity < 1.0:  # an opacity of 1 is no mask at all
                b = {"type": "mask", "opacity": opacity if isinstance(opacity, dict) else np.full(3, opacity), "bsdf": b}
        emissive = np.array(m.emissiveFactor or [0, 0, 0], float)
        strength = float(ext.get("KHR_materials_emissive_strength", {}).get("emissiveStrength", 1.0))
        emission_tex = None
        if m.emissiveTexture is not None and np.any(emissive > 0):
            img, smp = self.texels(m.emissiveTexture, f"{what}: emissiveTexture")
            emission_tex = (srgb_to_linear(img[..., :3]), smp)
            self.warn_once(("emissive", i), f"{what}: the emissiveTexture is averaged over each triangle (restir's area "
                           "lights have one radiance per triangle)")
        return b, emissive * strength, emission_tex
