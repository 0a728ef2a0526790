"""Perspective camera with Mitsuba's conventions and filter importance sampling.

Mitsuba's camera looks down +z of its local frame with +y up and +x toward the image's left.
The reconstruction filter is sampled (FIS): a sample's offset from the pixel centre is drawn
from the filter, and `CameraRay.weight` carries f/p where the filter is not sampled exactly.

A thin lens (Mitsuba 3's `thinlens`; aperture_radius > 0) starts each ray at a point drawn
uniformly on the aperture disc (concentric map) and aims it at the point of the plane in focus
(at focus_distance along the view axis) that the pinhole ray through the same image position
reaches; its weight is 1, as Mitsuba's. The aperture's numbers come from a stream of their own
(STAGE_LENS), so a pinhole camera's rays do not change.
"""
import warp as wp

from .rng import rng_key, rng_uniform2
from .sampling import sample_cdf, sample_tent, square_to_uniform_disk_concentric
from .streams import STAGE_CAMERA, STAGE_LENS
from .types import FILTER_BOX, FILTER_TENT


@wp.struct
class Camera:
    to_world: wp.mat44
    to_local: wp.mat44
    tan_half_x: float
    tan_half_y: float
    width: int
    height: int
    filter: int
    filter_radius: float
    # Gaussian (Mitsuba's: exp(-x^2/2s^2) minus its value at the radius), sampled from a
    # tabulated piecewise-constant pdf; the weight f(x) / (integral * p(x)) keeps it exact.
    filter_cdf: wp.array(dtype=float)      # bins+1 entries, cdf[0] = 0, cdf[bins] = 1
    filter_bins: int
    filter_stddev: float
    filter_inv_integral: float
    # 1: a sample's offset from the pixel centre is drawn from the filter (the image is the
    # filtered radiance, as in Mitsuba); 0: every primary ray goes through the pixel centre, so
    # a pixel sees one fixed primary hit and the image is the radiance at the centres (aliased
    # edges), as in the Suffix ReSTIR paper's evaluation. RenderConfig.jitter.
    jitter: int
    aperture_radius: float  # thin lens; 0: a pinhole
    focus_distance: float   # the plane in focus, along the view axis


@wp.struct
class CameraRay:
    o: wp.vec3
    d: wp.vec3
    weight: float


@wp.func
def gaussian_filter(cam: Camera, x: float) -> float:
    a = -1.0 / (2.0 * cam.filter_stddev * cam.filter_stddev)
    return wp.max(0.0, wp.exp(a * x * x) - wp.exp(a * cam.filter_radius * cam.filter_radius))


@wp.func
def sample_filter_1d(cam: Camera, u: float) -> wp.vec2:
    """Returns (offset in pixels, weight f(x) / (p(x) * integral f))."""
    if cam.filter == FILTER_BOX:
        return wp.vec2((u - 0.5) * 2.0 * cam.filter_radius, 1.0)
    if cam.filter == FILTER_TENT:
        return wp.vec2(cam.filter_radius * sample_tent(u), 1.0)
    n = cam.filter_bins
    i = sample_cdf(cam.filter_cdf, 0, n, u)
    c0 = cam.filter_cdf[i]
    c1 = cam.filter_cdf[i + 1]
    f = wp.clamp((u - c0) / wp.max(c1 - c0, 1.0e-30), 0.0, 0.999999)
    width = 2.0 * cam.filter_radius / float(n)
    x = -cam.filter_radius + (float(i) + f) * width
    return wp.vec2(x, gaussian_filter(cam, x) * cam.filter_inv_integral / ((c1 - c0) / width))


@wp.func
def generate_ray(cam: Camera, px: int, py: int, u: wp.vec2, u_lens: wp.vec2) -> CameraRay:
    """The ray through image position u of pixel (px, py), from aperture position u_lens (unused
    by a pinhole)."""
    fx = wp.vec2(0.0, 1.0)
    fy = wp.vec2(0.0, 1.0)
    if cam.jitter != 0:
        fx = sample_filter_1d(cam, u[0])
        fy = sample_filter_1d(cam, u[1])
    sx = (float(px) + 0.5 + fx[0]) / float(cam.width)
    sy = (float(py) + 0.5 + fy[0]) / float(cam.height)
    d_local = wp.vec3((1.0 - 2.0 * sx) * cam.tan_half_x, (1.0 - 2.0 * sy) * cam.tan_half_y, 1.0)
    r = CameraRay()
    r.weight = fx[1] * fy[1]
    if cam.aperture_radius > 0.0:
        a = square_to_uniform_disk_concentric(u_lens) * cam.aperture_radius
        on_lens = wp.vec3(a[0], a[1], 0.0)
        r.o = wp.transform_point(cam.to_world, on_lens)
        r.d = wp.normalize(wp.transform_vector(cam.to_world, d_local * cam.focus_distance - on_lens))
        return r
    r.o = wp.transform_point(cam.to_world, wp.vec3(0.0, 0.0, 0.0))
    r.d = wp.normalize(wp.transform_vector(cam.to_world, d_local))
    return r


@wp.func
def camera_ray(cam: Camera, seed: wp.uint32, frame: wp.uint32, pixel: int, sample: int) -> CameraRay:
    """The camera ray of sample `sample` of `pixel` in `frame`. Every method draws it from the one
    camera stream (stage STAGE_CAMERA), so renders with the same seed share their camera
    samples: comparisons between methods can use common random numbers (the directly seen
    emission, the same estimator everywhere, then cancels out of the difference)."""
    return generate_ray(cam, pixel % cam.width, pixel // cam.width, camera_u(seed, frame, pixel, sample),
                        lens_u(seed, frame, pixel, sample))


@wp.func
def camera_u(seed: wp.uint32, frame: wp.uint32, pixel: int, sample: int) -> wp.vec2:
    """The two uniform numbers camera_ray turns into the sample's position in the pixel."""
    key = rng_key(seed, frame, wp.uint32(STAGE_CAMERA), wp.uint32(pixel))
    return rng_uniform2(key, wp.uint32(2) * wp.uint32(sample))


@wp.func
def lens_u(seed: wp.uint32, frame: wp.uint32, pixel: int, sample: int) -> wp.vec2:
    """The two uniform numbers camera_ray turns into the sample's position on the aperture."""
    key = rng_key(seed, frame, wp.uint32(STAGE_LENS), wp.uint32(pixel))
    return rng_uniform2(key, wp.uint32(2) * wp.uint32(sample))


@wp.func
def lattice_u(u: wp.vec2, j: int, n: int) -> wp.vec2:
    """Point j of n of a lattice shifted by u (point 0 is u itself), modulo 1: the positions of the
    `emission.rays` camera rays of a sample. Each point is uniform because u is, so each ray's
    emission is an unbiased estimate of the pixel's; the lattice spreads the n rays over the pixel
    (j / n along x, one point per stratum; j times the golden ratio's fractional part along y)."""
    g = wp.vec2(float(j) / float(n), float(j) * 0.6180339887498949)
    x = u + g
    return wp.vec2(x[0] - wp.floor(x[0]), x[1] - wp.floor(x[1]))


@wp.func
def project_to_pixel(cam: Camera, p: wp.vec3) -> wp.vec2:
    """Continuous pixel coordinates of world point p (pixel centres at i + 0.5); (-1, -1) when
    p is behind the camera. Inverse of generate_ray's mapping."""
    q = wp.transform_point(cam.to_local, p)
    if q[2] <= 0.0:
        return wp.vec2(-1.0, -1.0)
    sx = 0.5 * (1.0 - q[0] / (q[2] * cam.tan_half_x))
    sy = 0.5 * (1.0 - q[1] / (q[2] * cam.tan_half_y))
    return wp.vec2(sx * float(cam.width), sy * float(cam.height))
