"""Embree 4 on the CPU through ctypes: the library bundled in the `embreex` wheel.

Builds one triangle scene (robust/watertight, high build quality) from the same un-indexed
vertex array as the Warp mesh, and exposes the scene handle and the addresses of
`rtcIntersect1` / `rtcOccluded1` as integers for the native snippets in
device/native_trace.py. Returns None where Embree is unavailable; callers fall back to Warp.
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
RTC_SCENE_FLAG_ROBUST = 1 << 2
RTC_BUILD_QUALITY_HIGH = 2

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
    lib.rtcReleaseGeometry.argtypes = [vp]
    lib.rtcCommitScene.argtypes = [vp]
    lib.rtcReleaseScene.argtypes = [vp]
    lib.rtcReleaseDevice.argtypes = [vp]
    lib.rtcGetDeviceError.restype, lib.rtcGetDeviceError.argtypes = ctypes.c_int, [vp]
    _lib = lib
    return lib


class EmbreeScene:
    """One committed Embree scene over un-indexed triangles (positions: (T, 3, 3) float32)."""

    def __init__(self, positions: np.ndarray):
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
        lib.rtcSetSceneFlags(self.scene, RTC_SCENE_FLAG_ROBUST)
        lib.rtcSetSceneBuildQuality(self.scene, RTC_BUILD_QUALITY_HIGH)
        geom = lib.rtcNewGeometry(self.device, RTC_GEOMETRY_TYPE_TRIANGLE)
        lib.rtcSetGeometryBuildQuality(geom, RTC_BUILD_QUALITY_HIGH)
        # Embree may read 16 bytes from the last vertex: allocate with room to spare.
        vbuf = lib.rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 12, len(tri) + 1)
        ibuf = lib.rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 12, n)
        ctypes.memmove(vbuf, tri.ctypes.data, tri.nbytes)
        idx = np.arange(3 * n, dtype=np.uint32)
        ctypes.memmove(ibuf, idx.ctypes.data, idx.nbytes)
        lib.rtcCommitGeometry(geom)
        lib.rtcAttachGeometry(self.scene, geom)
        lib.rtcReleaseGeometry(geom)
        lib.rtcCommitScene(self.scene)
        err = lib.rtcGetDeviceError(self.device)
        if err != 0:
            raise RuntimeError(f"Embree error {err} while building the scene")
        self.intersect_fn = ctypes.cast(lib.rtcIntersect1, ctypes.c_void_p).value
        self.occluded_fn = ctypes.cast(lib.rtcOccluded1, ctypes.c_void_p).value

    def __del__(self):
        try:
            self.lib.rtcReleaseScene(self.scene)
            self.lib.rtcReleaseDevice(self.device)
        except Exception:
            pass
