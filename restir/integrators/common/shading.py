"""A pixel's primary hit rebuilt from a G-buffer: everything a target function needs there."""
import warp as wp

from ...device.bsdf import Material
from ...device.bounce import material_at, shading_frame
from ...device.intersect import SurfaceHit, surface_at
from ...device.sampling import Frame, to_local
from ...device.scene_device import SceneDevice
from .gbuffer import GBuffer


@wp.struct
class Shading:
    """Everything the target p_hat needs at one primary hit."""
    valid: int
    hit: SurfaceHit
    frame: Frame
    wi: wp.vec3      # direction to the camera, local
    mat: Material


# Forced inline (as temporal_neighbor and spatial_technique, reuse_domains.py): Warp passes structs
# by value, so out of line each call copies the whole SceneDevice (about 1 KB) and returns a
# Shading. The opacity-mask lookup in material_at pushed this function out of line under the CPU
# compiler's inlining budget, and ReSTIR DI's visibility, temporal, spatial and shade stages took
# 1.3-1.8x as long (docs/changelog.md#speed-load_shading-forced-inline).
@wp.func(inline=True)
def load_shading(scene: SceneDevice, gb: GBuffer, pixel: int) -> Shading:
    s = Shading()
    tri = gb.tri[pixel]
    s.valid = 0
    if tri < 0:
        return s
    b = gb.bary[pixel]
    s.hit = surface_at(scene, tri, b[0], b[1], 0.0)
    d = wp.vec3(0.0)
    if gb.from_camera != 0:  # the primary ray, rebuilt: camera position -> hit (gbuffer.py)
        to_hit = s.hit.p - gb.origin
        s.hit.t = wp.length(to_hit)
        d = to_hit / s.hit.t
    else:
        s.hit.t = gb.t[pixel]
        d = gb.dir[pixel]
    s.frame = shading_frame(scene, s.hit, -d)
    s.mat = material_at(scene, s.hit, s.frame)
    s.wi = to_local(s.frame, -d)
    s.valid = 1
    return s


@wp.func(inline=False)
def load_shading_outlined(scene: SceneDevice, gb: GBuffer, pixel: int) -> Shading:
    """load_shading kept out of line, for a kernel that calls it once before a long loop (ReSTIR
    DI's initial candidates): one copy per pixel, and the loop's code stays compact; inlined
    there, the stage took 6% longer (docs/changelog.md#speed-llvms-inline-threshold-40000)."""
    return load_shading(scene, gb, pixel)


@wp.func
def similar_surfaces(a: Shading, b: Shading) -> bool:
    """Neighbour test on geometry only (ReSTIR PT's): normals within 60 deg, depth within 10%."""
    return wp.dot(a.hit.ns, b.hit.ns) >= 0.5 and wp.abs(a.hit.t - b.hit.t) < 0.1 * a.hit.t
