"""Counter-based random numbers keyed by (seed, frame, stage, pixel, dimension).

There is no hidden state: a number is a pure function of its key, so any stage can regenerate
any path's numbers (random replay) and results do not depend on launch order or slicing.
"""
import warp as wp

# Typed constants: literals above 2^31 would otherwise be emitted as int32.
_M1 = wp.constant(wp.uint32(0x7FEB352D))
_M2 = wp.constant(wp.uint32(0x846CA68B))
_GOLDEN = wp.constant(wp.uint32(0x9E3779B9))
_SEED_SALT = wp.constant(wp.uint32(0x68E31DA4))


@wp.func
def hash_u32(x: wp.uint32) -> wp.uint32:
    # "lowbias32" integer finalizer (Wellons): full avalanche, cheap.
    x = x ^ (x >> wp.uint32(16))
    x = x * _M1
    x = x ^ (x >> wp.uint32(15))
    x = x * _M2
    x = x ^ (x >> wp.uint32(16))
    return x


@wp.func
def hash_combine(h: wp.uint32, v: wp.uint32) -> wp.uint32:
    return hash_u32(h ^ (hash_u32(v) + _GOLDEN + (h << wp.uint32(6)) + (h >> wp.uint32(2))))


@wp.func
def rng_key(seed: wp.uint32, frame: wp.uint32, stage: wp.uint32, pixel: wp.uint32) -> wp.uint32:
    """Stream key of one (seed, frame, stage, pixel); combine with a dimension in rng_uniform."""
    h = hash_u32(seed + _SEED_SALT)
    h = hash_combine(h, frame)
    h = hash_combine(h, stage)
    h = hash_combine(h, pixel)
    return h


@wp.func
def u32_to_unit_float(x: wp.uint32) -> float:
    # 24 high bits -> [0, 1): exactly representable, never returns 1.
    return float(x >> wp.uint32(8)) * (1.0 / 16777216.0)


@wp.func
def rng_uniform(key: wp.uint32, dim: wp.uint32) -> float:
    return u32_to_unit_float(hash_combine(key, dim))


@wp.func
def rng_uniform2(key: wp.uint32, dim: wp.uint32) -> wp.vec2:
    return wp.vec2(rng_uniform(key, dim), rng_uniform(key, dim + wp.uint32(1)))
