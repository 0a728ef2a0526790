"""Scalar summaries of RGB values used by targets and estimators."""
import warp as wp


@wp.func
def luminance(c: wp.vec3) -> float:
    """Rec. 709 luminance: the scalar target p_hat of an RGB integrand (Conditional ReSTIR's choice)."""
    return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]


@wp.func
def max3(v: wp.vec3) -> float:
    return wp.max(wp.max(v[0], v[1]), v[2])
