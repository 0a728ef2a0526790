"""glTF buffers, accessors and images as numpy arrays, each checked against the file's own sizes
(a broken or hostile file is an error naming what is wrong, never an out-of-bounds read)."""
import base64
import io
import os
import urllib.parse

import numpy as np

from ..errors import SceneError

COMPONENTS = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16, 5125: np.uint32, 5126: np.float32}
WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}
NORMALIZE = {np.int8: 127.0, np.uint8: 255.0, np.int16: 32767.0, np.uint16: 65535.0}


class Buffers:
    def __init__(self, gltf, path: str):
        self.gltf, self.path = gltf, path
        self.base_dir = os.path.dirname(os.path.abspath(path))
        self.cache: dict[int, bytes] = {}

    def uri_bytes(self, uri: str, what: str) -> bytes:
        if uri.startswith("data:"):
            head, _, data = uri.partition(",")
            if not head.endswith(";base64"):
                raise SceneError(f"{what}: only base64 data URIs are supported", self.path)
            try:
                return base64.b64decode(data, validate=False)
            except ValueError as e:
                raise SceneError(f"{what}: a data URI that is not base64 ({e})", self.path) from None
        name = urllib.parse.unquote(uri)
        full = name if os.path.isabs(name) else os.path.join(self.base_dir, name)
        if not os.path.isfile(full):
            raise SceneError(f"{what}: file '{name}' not found", self.path)
        with open(full, "rb") as f:
            return f.read()

    def buffer(self, i: int) -> bytes:
        if i not in self.cache:
            bufs = self.gltf.buffers or []
            if not 0 <= i < len(bufs):
                raise SceneError(f"buffer {i} does not exist", self.path)
            b = bufs[i]
            if b.uri is None:  # the GLB's binary chunk
                data = self.gltf.binary_blob()
                if data is None:
                    raise SceneError(f"buffer {i} has no uri and the file has no binary chunk", self.path)
            else:
                data = self.uri_bytes(b.uri, f"buffer {i}")
            if b.byteLength is not None and len(data) < b.byteLength:
                raise SceneError(f"buffer {i} holds {len(data)} bytes, fewer than its byteLength {b.byteLength}",
                                 self.path)
            self.cache[i] = data
        return self.cache[i]

    def view_bytes(self, v: int) -> tuple[bytes, int, int, int | None]:
        views = self.gltf.bufferViews or []
        if not 0 <= v < len(views):
            raise SceneError(f"bufferView {v} does not exist", self.path)
        bv = views[v]
        data = self.buffer(bv.buffer)
        off = bv.byteOffset or 0
        if off < 0 or off + bv.byteLength > len(data):
            raise SceneError(f"bufferView {v} reaches past the end of buffer {bv.buffer}", self.path)
        return data, off, bv.byteLength, bv.byteStride

    def accessor(self, a: int, what: str) -> np.ndarray:
        """Accessor `a` as float64 (N, width) (normalized integers scaled to [0, 1] or [-1, 1]),
        or int64 for integer accessors that are not normalized."""
        accs = self.gltf.accessors or []
        if a is None or not 0 <= a < len(accs):
            raise SceneError(f"{what}: accessor {a} does not exist", self.path)
        acc = accs[a]
        if acc.sparse is not None:
            raise SceneError(f"{what}: sparse accessors are not supported", self.path)
        if acc.componentType not in COMPONENTS or acc.type not in WIDTH:
            raise SceneError(f"{what}: accessor {a} has an unknown componentType or type", self.path)
        dtype = np.dtype(COMPONENTS[acc.componentType]).newbyteorder("<")
        width, n = WIDTH[acc.type], acc.count
        if acc.bufferView is None:
            out = np.zeros((n, width), dtype)
        else:
            data, off, length, stride = self.view_bytes(acc.bufferView)
            off += acc.byteOffset or 0
            elem = dtype.itemsize * width
            stride = stride or elem
            if n and off + stride * (n - 1) + elem > len(data) or stride < elem:
                raise SceneError(f"{what}: accessor {a} reaches past the end of its bufferView", self.path)
            out = np.ndarray((n, width), dtype, buffer=data, offset=off, strides=(stride, dtype.itemsize)).copy()
        if acc.normalized and out.dtype.kind in "iu":
            scale = NORMALIZE[COMPONENTS[acc.componentType]]
            return np.maximum(out.astype(np.float64) / scale, -1.0)
        if out.dtype.kind == "f":
            out = out.astype(np.float64)
            if not np.all(np.isfinite(out)):
                raise SceneError(f"{what}: accessor {a} holds a value that is not finite", self.path)
            return out
        return out.astype(np.int64)

    def image(self, i: int) -> np.ndarray:
        """Image `i` decoded as float (H, W, 4) in [0, 1], not linearized (colour textures are
        sRGB-encoded, data textures linear: the caller knows which)."""
        imgs = self.gltf.images or []
        if not 0 <= i < len(imgs):
            raise SceneError(f"image {i} does not exist", self.path)
        im = imgs[i]
        if im.uri is not None:
            data = self.uri_bytes(im.uri, f"image {i}")
        elif im.bufferView is not None:
            buf, off, length, _ = self.view_bytes(im.bufferView)
            data = buf[off:off + length]
        else:
            raise SceneError(f"image {i} has neither a uri nor a bufferView", self.path)
        from PIL import Image

        try:
            with Image.open(io.BytesIO(data)) as pil:
                arr = np.asarray(pil.convert("RGBA"), np.float32) / np.float32(255.0)
        except Exception as e:  # PIL raises many types for unreadable images
            raise SceneError(f"image {i}: not a readable PNG or JPEG ({type(e).__name__}: {e})", self.path) from None
        if arr.shape[0] < 1 or arr.shape[1] < 1:
            raise SceneError(f"image {i} has no pixels", self.path)
        return arr
