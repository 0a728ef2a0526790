"""The steps of a unidirectional path, as device functions with plain arguments and explicit
random numbers: a light connection (next-event estimation) at a vertex, the MIS weight of
emission found by BSDF sampling, one BSDF scattering step, and Russian roulette.

`--method pt` is a loop over these (integrators/path.py); ReSTIR PT's base path and random replay
call the same functions, so the three trace the same paths from the same numbers.

MIS: N light samples per vertex and one BSDF sample are combined by the balance heuristic over
N p_light + p_bsdf (both solid-angle densities at the vertex). `strategy` switches the estimator
to NEE-only or BSDF-only, two other estimators of the same integral used as cross-checks.

The two large steps are force-inlined (`inline=True`): called out of line they take the material
and hit structs by value at each call, and the path tracer ran 5-8% slower on the CPU (same-run
A/B, docs/changelog.md#speed-the-path-tracers-large-steps-inlined).
"""
import warp as wp

from .bsdf import BSDFSample, Material, bsdf_eval, bsdf_pdf, bsdf_sample
from .color import max3
from .intersect import SurfaceHit, offset_origin, visible_to_light
from .lights import sample_light
from .sampling import Frame, to_local, to_world
from .scene_device import SceneDevice
from .types import STRATEGY_BSDF, STRATEGY_MIS, STRATEGY_NEE

RR_MAX_SURVIVAL = wp.constant(0.95)  # Mitsuba's cap on the survival probability


@wp.func
def emission_mis_weight(prev_delta: int, p_bsdf: float, p_light: float, light_samples: int, strategy: int) -> float:
    """Weight of emission reached by BSDF sampling with density p_bsdf, where light sampling
    would have produced the same point with density p_light (camera rays and delta bounces: 1)."""
    if prev_delta != 0 or strategy == STRATEGY_BSDF:
        return 1.0
    if strategy == STRATEGY_NEE:
        return 0.0
    return p_bsdf / (p_bsdf + float(light_samples) * p_light)


@wp.struct
class LightConnection:
    L: wp.vec3        # this light sample's share of the vertex's NEE estimate: f Le V w / (N p_light)
    Le: wp.vec3       # emitted radiance arriving along wi (0 when the sample failed)
    wi: wp.vec3       # unit world direction toward the light
    p_light: float    # solid-angle density of the light sample, selection included (0: failed);
                      # a delta light's selection probability
    p_bsdf: float     # BSDF sampling density of wi (for MIS; 0 unless strategy is MIS; 0 for a delta light)
    is_delta: int     # the light is a delta light: no other technique reaches it, MIS weight 1
    rays: int         # shadow rays traced (0 or 1)


@wp.func(inline=True)
def connect_to_light(scene: SceneDevice, hit: SurfaceHit, mat: Material, frame: Frame, wi: wp.vec3, u_select: float,
                     u_point: wp.vec2, light_samples: int, strategy: int) -> LightConnection:
    """One of the N light samples at a vertex (wi: the local direction toward the previous vertex)."""
    c = LightConnection()
    ls = sample_light(scene, hit.p, u_select, u_point)
    c.wi = ls.wi
    c.p_light = ls.pdf
    c.is_delta = ls.is_delta
    # BSDF sampling never reaches a delta light, so the BSDF-only estimator has no term for it:
    # its light is NEE's alone whatever the strategy (the set of techniques is the light's kind)
    if ls.pdf > 0.0 and max3(ls.Le) > 0.0 and (strategy != STRATEGY_BSDF or ls.is_delta != 0):
        wo = to_local(frame, ls.wi)
        f = bsdf_eval(mat, wi, wo)
        if max3(f) > 0.0:
            c.rays = 1
            if visible_to_light(scene, hit.p, hit.ng, ls.wi, ls.p, ls.n, ls.infinite):
                c.Le = ls.Le
                p_sum = float(light_samples) * ls.pdf
                if strategy == STRATEGY_MIS and ls.is_delta == 0:
                    c.p_bsdf = bsdf_pdf(mat, wi, wo)
                    p_sum += c.p_bsdf
                c.L = wp.cw_mul(f, ls.Le) / p_sum
    return c


@wp.struct
class Scatter:
    bs: BSDFSample    # the BSDF sample in the local frame (weight = f |cos| / pdf, lobe, pdf)
    d: wp.vec3        # its world direction
    o: wp.vec3        # the next ray's origin, offset off the surface
    valid: int


@wp.func(inline=True)
def scatter(hit: SurfaceHit, mat: Material, frame: Frame, wi: wp.vec3, u_lobe: float, u_dir: wp.vec2) -> Scatter:
    """One BSDF sampling step at a vertex (wi local, toward the previous vertex)."""
    s = Scatter()
    s.bs = bsdf_sample(mat, wi, u_lobe, u_dir)
    s.valid = s.bs.valid
    if s.valid != 0:
        s.d = wp.normalize(to_world(frame, s.bs.wo))
        s.o = offset_origin(hit.p, hit.ng, s.d)
    return s


@wp.func
def rr_survival_probability(beta: wp.vec3, eta: float) -> float:
    """Mitsuba's Russian-roulette rule: survive with min(max(beta) eta^2, 0.95), where beta is the
    throughput so far (already divided by earlier survival probabilities) and eta the relative
    IOR crossed (radiance is compressed by 1/eta^2 on refraction)."""
    return wp.min(max3(beta) * eta * eta, RR_MAX_SURVIVAL)
