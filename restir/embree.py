"""Embree 4 on the CPU through ctypes: the library bundled in the `embreex` wheel.

Builds one triangle scene (robust/watertight, high build quality) from the same un-indexed
vertex array as the Warp mesh, and exposes the scene handle and the addresses of
`rtcIntersect1` / `rtcOccluded1` as integers for the native snippets in
device/native_trace.py. Returns None where Embree is unavailable; callers fall back to Warp.

A scene whose objects move (scene/animation.py) is built as one geometry per contiguous range
of triangles, the moving objects' ranges apart, in a dynamic scene: Embree then keeps a BVH per
geometry under a top-level one, and `update` refits the moving geometries' BVHs alone. Each
geometry's ID is its first triangle, so a hit's triangle is geomID + primID (one geometry: 0 +
primID), which the snippets read without a table.
"""
import ctypes
import glob
import os

import numpy as np

RTC_GEOMETRY_TYPE_TRIANGLE = 0
RTC_BUFFER_TYPE_INDEX = 0
RTC_BUFFER_TYPE_VERTEX = 1
RTC_FORMAT_UINT3 = 0x5003
RTC_FORMAT_FLOAT3 = 0x9003
RTC_SCENE_FLAG_DYNAMIC = 1 << 0
RTC_SCENE_FLAG_ROBUST = 1 << 2
RTC_BUILD_QUALITY_LOW = 0
RTC_BUILD_QUALITY_HIGH = 2
RTC_BUILD_QUALITY_REFIT = 3

_lib = None


def library():
    """The Embree 4 shared library, or None."""
    global _lib
    if _lib is not None:
        return _lib or None
    try:
        import embreex

        base = os.path.dirname(os.path.dirname(embreex.__file__))
        paths = glob.glob(os.path.join(base, "embreex.libs", "libembree4*.so*"))
        lib = ctypes.CDLL(paths[0], mode=ctypes.RTLD_GLOBAL)
    except (ImportError, IndexError, OSError):
        _lib = False
        return None
    vp, u32, sz = ctypes.c_void_p, ctypes.c_uint, ctypes.c_size_t
    lib.rtcNewDevice.restype, lib.rtcNewDevice.argtypes = vp, [ctypes.c_char_p]
    lib.rtcNewScene.restype, lib.rtcNewScene.argtypes = vp, [vp]
    lib.rtcSetSceneFlags.argtypes = [vp, ctypes.c_int]
    lib.rtcSetSceneBuildQuality.argtypes = [vp, ctypes.c_int]
    lib.rtcNewGeometry.restype, lib.rtcNewGeometry.argtypes = vp, [vp, ctypes.c_int]
    lib.rtcSetNewGeometryBuffer.restype = vp
    lib.rtcSetNewGeometryBuffer.argtypes = [vp, ctypes.c_int, u32, ctypes.c_int, sz, sz]
    lib.rtcSetGeometryBuildQuality.argtypes = [vp, ctypes.c_int]
    lib.rtcCommitGeometry.argtypes = [vp]
    lib.rtcAttachGeometry.restype, lib.rtcAttachGeometry.argtypes = u32, [vp, vp]
    lib.rtcAttachGeometryByID.argtypes = [vp, vp, u32]
    lib.rtcUpdateGeometryBuffer.argtypes = [vp, ctypes.c_int, u32]
    lib.rtcReleaseGeometry.argtypes = [vp]
    lib.rtcCommitScene.argtypes = [vp]
    lib.rtcReleaseScene.argtypes = [vp]
    lib.rtcReleaseDevice.argtypes = [vp]
    lib.rtcGetDeviceError.restype, lib.rtcGetDeviceError.argtypes = ctypes.c_int, [vp]
    _lib = lib
    return lib


def _ranges(n: int, dynamic) -> list:
    """[(first, stop, moving)] covering triangles 0..n-1: the moving ranges and the gaps between."""
    out, at = [], 0
    for lo, hi in sorted(dynamic):
        if lo > at:
            out.append((at, lo, False))
        out.append((lo, hi, True))
        at = hi
    if at < n:
        out.append((at, n, False))
    return out


class EmbreeScene:
    """One committed Embree scene over un-indexed triangles (positions: (T, 3, 3) float32).
    dynamic: the triangle ranges [lo, hi) that move (disjoint); `update` then refits them alone."""

    def __init__(self, positions: np.ndarray, dynamic=()):
        lib = library()
        if lib is None:
            raise RuntimeError("Embree is not available")
        tri = np.ascontiguousarray(positions, np.float32).reshape(-1, 3)
        n = len(tri) // 3
        if n >= 1 << 24:
            raise ValueError("more than 2^24 triangles: triangle ids would not survive the float transport")
        self.lib = lib
        self.device = lib.rtcNewDevice(None)
        if not self.device:
            raise RuntimeError("rtcNewDevice failed")
        self.scene = lib.rtcNewScene(self.device)
        dynamic = [(int(lo), int(hi)) for lo, hi in dynamic if hi > lo]
        lib.rtcSetSceneFlags(self.scene, RTC_SCENE_FLAG_ROBUST | (RTC_SCENE_FLAG_DYNAMIC if dynamic else 0))
        # a dynamic scene at low quality is what makes Embree keep a BVH per geometry under a top
        # level (measured at 10^6 triangles, 1% moving: an update took 5 ms; at the high quality
        # of a static scene, 170 ms, a rebuild of everything); each static geometry's own BVH stays
        # at high quality
        lib.rtcSetSceneBuildQuality(self.scene, RTC_BUILD_QUALITY_LOW if dynamic else RTC_BUILD_QUALITY_HIGH)
        self.moving = []  # (geometry, vertex buffer address, first, stop) of each moving range
        for lo, hi, moves in _ranges(n, dynamic):
            geom = lib.rtcNewGeometry(self.device, RTC_GEOMETRY_TYPE_TRIANGLE)
            lib.rtcSetGeometryBuildQuality(geom, RTC_BUILD_QUALITY_REFIT if moves else RTC_BUILD_QUALITY_HIGH)
            count = hi - lo
            # Embree may read 16 bytes from the last vertex: allocate with room to spare.
            vbuf = lib.rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 12, 3 * count + 1)
            ibuf = lib.rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 12, count)
            part = tri[3 * lo:3 * hi]
            ctypes.memmove(vbuf, part.ctypes.data, part.nbytes)
            idx = np.arange(3 * count, dtype=np.uint32)
            ctypes.memmove(ibuf, idx.ctypes.data, idx.nbytes)
            lib.rtcCommitGeometry(geom)
            lib.rtcAttachGeometryByID(self.scene, geom, lo)  # the geometry's ID is its first triangle
            if moves:
                self.moving.append((geom, vbuf, lo, hi))
            else:
                lib.rtcReleaseGeometry(geom)
        lib.rtcCommitScene(self.scene)
        self._check("building the scene")
        self.intersect_fn = ctypes.cast(lib.rtcIntersect1, ctypes.c_void_p).value
        self.occluded_fn = ctypes.cast(lib.rtcOccluded1, ctypes.c_void_p).value

    def _check(self, what: str) -> None:
        err = self.lib.rtcGetDeviceError(self.device)
        if err != 0:
            raise RuntimeError(f"Embree error {err} while {what}")

    @property
    def dynamic(self) -> list:
        return [(lo, hi) for _, _, lo, hi in self.moving]

    def update(self, parts: dict) -> None:
        """Moving ranges moved: parts {first triangle: its range's positions (n, 3, 3)}, each a range
        given at construction; their BVHs refitted, the top level rebuilt, the rest kept."""
        by_first = {lo: (geom, vbuf, hi) for geom, vbuf, lo, hi in self.moving}
        for lo, pos in parts.items():
            geom, vbuf, hi = by_first[lo]
            part = np.ascontiguousarray(pos, np.float32).reshape(-1, 3)
            if len(part) != 3 * (hi - lo):
                raise ValueError(f"triangles {lo}..{hi}: {len(part)} vertices given")
            ctypes.memmove(vbuf, part.ctypes.data, part.nbytes)
            self.lib.rtcUpdateGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0)
            self.lib.rtcCommitGeometry(geom)
        self.lib.rtcCommitScene(self.scene)
        self._check("updating the scene")

    def __del__(self):
        try:
            for geom, *_ in self.moving:
                self.lib.rtcReleaseGeometry(geom)
            self.lib.rtcReleaseScene(self.scene)
            self.lib.rtcReleaseDevice(self.device)
        except Exception:
            pass
