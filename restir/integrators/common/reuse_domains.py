"""Which other pixels' reservoirs a pixel may reuse: the previous frame's pixel that saw the same
point (temporal) and nearby pixels (spatial). Both choices depend on geometry and screen position
only, never on reservoir contents, so the set of MIS techniques is fixed before sampling.
"""

import warp as wp

from ...device.camera import Camera, project_to_pixel
from ...device.intersect import surface_at
from ...device.sampling import square_to_uniform_disk_concentric
from ...device.scene_device import SceneDevice
from .gbuffer import GBuffer
from .shading import Shading, load_shading, similar_surfaces

NO_PIXEL = wp.constant(-1)

# Spatial radii are given for 1080-line images (the literature's: ReSTIR DI 30 px, ReSTIR PT
# 20 px); `spatial_radius_for` scales them up for taller images, one rule for every method.
REFERENCE_LINES = 1080.0

@wp.func
def reproject(camera: Camera, prev_camera: Camera, pixel: int, p: wp.vec3, p_prev: wp.vec3) -> int:
    """The previous frame's pixel of `pixel`, whose primary hit this frame is p and was p_prev
    the frame before (the same point of its surface before that surface moved): the pixel moved by
    the point's motion on screen (p_prev under the previous camera less p under this one);
    NO_PIXEL when p_prev was behind that camera or the moved pixel is off screen. Not the pixel
    whose square holds p under the previous camera: the primary ray's filter offset reaches into
    the neighbouring pixels (a tent or Gaussian filter), so a pixel's
    history would come from a neighbour in a third of the frames even under a still camera, and
    the samples would wander between pixels, frame after frame: an error correlated between
    neighbours that the denoiser keeps (docs/guide/when_restir_pays.md#what-the-denoiser-keeps-correlated-error)."""
    cur = project_to_pixel(camera, p)
    prev = project_to_pixel(prev_camera, p_prev)
    if prev[0] == -1.0 and prev[1] == -1.0:  # project_to_pixel's answer for a point behind the camera
        return NO_PIXEL
    x = float(pixel % camera.width) + 0.5 + (prev[0] - cur[0])
    y = float(pixel // camera.width) + 0.5 + (prev[1] - cur[1])
    qx = int(wp.floor(x))
    qy = int(wp.floor(y))
    if x < 0.0 or y < 0.0 or qx >= prev_camera.width or qy >= prev_camera.height:
        return NO_PIXEL
    return qy * prev_camera.width + qx

@wp.func
def spatial_neighbor(u: wp.vec2, pixel: int, width: int, height: int, radius: float) -> int:
    """A pixel drawn uniformly (by area, then rounded) in a disk of `radius` pixels around `pixel`,
    from the two uniform numbers u; NO_PIXEL when it falls off screen or on the pixel itself."""
    px = pixel % width
    py = pixel // width
    o = square_to_uniform_disk_concentric(u) * radius
    nx = px + int(wp.round(o[0]))
    ny = py + int(wp.round(o[1]))
    if nx < 0 or ny < 0 or nx >= width or ny >= height or (nx == px and ny == py):
        return NO_PIXEL
    return ny * width + nx

@wp.func
def reciprocal_pairing(radius: float, u_mask: wp.vec2, u_shift: wp.vec2) -> wp.vec4i:
    """One reciprocal draw (spatial.reciprocal), the same for every pixel of a frame: a mask
    (a, b) from a disk of `radius` pixels (u_mask; never (0, 0)) and a shift (tx, ty) of the grid
    (u_shift, below the mask's power-of-two period). See reciprocal_partner."""
    o = square_to_uniform_disk_concentric(u_mask) * radius
    a = wp.abs(int(wp.round(o[0])))
    b = wp.abs(int(wp.round(o[1])))
    if a == 0 and b == 0:
        a = 1  # a pixel is never its own neighbour
    period_x = int(1)
    while period_x <= a:
        period_x = period_x * 2
    period_y = int(1)
    while period_y <= b:
        period_y = period_y * 2
    tx = wp.min(int(u_shift[0] * float(period_x)), period_x - 1)
    ty = wp.min(int(u_shift[1] * float(period_y)), period_y - 1)
    return wp.vec4i(a, b, tx, ty)


@wp.func
def reciprocal_partner(pixel: int, width: int, height: int, pairing: wp.vec4i) -> int:
    """The pixel paired with `pixel` by a reciprocal draw (a, b, tx, ty) (reciprocal_pairing), or
    NO_PIXEL when that falls off screen: (x, y) is paired with (((x + tx) ^ a) - tx,
    ((y + ty) ^ b) - ty). XOR with a fixed mask is an involution, so partner(partner(p)) = p:
    every pixel is the neighbour of its own neighbour (a perfect matching of the screen), which is
    what lets one thread shift a pair's two samples for both. |x' - x| <= a and |y' - y| <= b, so
    the partner lies within the draw's radius (plus the rounding of a and b: 0.71 px at most).
    The offset varies from pixel to pixel with the bits of x + tx (a = 3 gives -3, -1, 1 or 3),
    and the shift moves the 2^n-aligned blocks the pairs live in from draw to draw."""
    px = pixel % width
    py = pixel // width
    nx = ((px + pairing[2]) ^ pairing[0]) - pairing[2]
    ny = ((py + pairing[3]) ^ pairing[1]) - pairing[3]
    if nx < 0 or ny < 0 or nx >= width or ny >= height:
        return NO_PIXEL
    return ny * width + nx


@wp.struct
class Neighbor:
    """A pixel whose reservoir a pixel may reuse, with its primary hit; pixel = NO_PIXEL: none."""
    pixel: int
    sh: Shading


@wp.func(inline=True)  # as load_shading: out of line it copies SceneDevice and a Shading
def temporal_neighbor(prev_scene: SceneDevice, motion_scene: SceneDevice, camera: Camera, prev_camera: Camera,
                      prev_gb: GBuffer, sc: Shading, pixel: int) -> Neighbor:
    """The temporal technique of `pixel`, with primary hit sc: its previous frame's pixel
    (`reproject`), if that had a primary hit and the two surfaces are similar. The motion vector
    is the hit's own: its point (triangle and barycentrics) where `motion_scene` had it (the
    previous frame's scene; with a moving object, the camera's motion alone would point to where
    the object was not). The previous hit is rebuilt in `prev_scene`, the domain it belongs to."""
    n = Neighbor()
    p_prev = surface_at(motion_scene, sc.hit.tri, sc.hit.bary[0], sc.hit.bary[1], 0.0).p
    n.pixel = reproject(camera, prev_camera, pixel, sc.hit.p, p_prev)
    if n.pixel != NO_PIXEL:
        n.sh = load_shading(prev_scene, prev_gb, n.pixel)
        if n.sh.valid == 0 or not similar_surfaces(sc, n.sh):
            n.pixel = NO_PIXEL
    return n


@wp.func(inline=True)  # as load_shading
def spatial_technique(scene: SceneDevice, gb: GBuffer, u: wp.vec2, pixel: int, width: int, height: int,
                      radius: float, sc: Shading) -> Neighbor:
    """One spatial technique of a pixel with primary hit sc: a pixel drawn in the disk
    (spatial_neighbor), kept if it has a primary hit similar to sc."""
    n = Neighbor()
    n.pixel = spatial_neighbor(u, pixel, width, height, radius)
    if n.pixel != NO_PIXEL:
        n.sh = load_shading(scene, gb, n.pixel)
        if n.sh.valid == 0 or not similar_surfaces(sc, n.sh):
            n.pixel = NO_PIXEL
    return n


def spatial_radius_for(radius_at_1080: float, height: int) -> float:
    """The spatial reuse radius in pixels for an image `height` lines high, from a radius given for
    1080 lines: that many pixels up to 1080 lines, scaled with the height above (neighbours then
    cover the same part of the scene). Not scaled down: a denoiser works in pixels, and a reuse
    copies a neighbour's sample, so a disk of a few pixels puts copies of one sample next to each
    other, an error the denoiser keeps as detail. At 128 lines ReSTIR PT's error after Open Image
    Denoise was 1.4-6x the path tracer's at equal time with the disk scaled down to 2.4 px, and
    1.1-1.4x lower with 16-24 px on three of four scenes (docs/guide/when_restir_pays.md#the-spatial-radius)."""
    return radius_at_1080 * max(1.0, height / REFERENCE_LINES)



def resolve_spatial_radius(setting, radius_at_1080: float, height: int) -> float:
    """A method's `spatial.radius` setting in pixels: "auto" (the default) scales the method's
    1080-line radius with the image; a number is taken as pixels."""
    if setting == "auto":
        return spatial_radius_for(radius_at_1080, height)
    try:
        radius = float(setting)
    except (TypeError, ValueError):
        radius = -1.0
    if not radius > 0.0:
        from ...config import ConfigError

        raise ConfigError(f"spatial.radius must be 'auto' or a positive number of pixels, not '{setting}'")
    return radius
