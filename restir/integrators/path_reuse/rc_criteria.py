"""Which vertex of a path is its reconnection (rc) vertex, and the lobe-separated path BSDF.

Hybrid shift (docs/theory/restir_pt.md#the-reconnection-vertex): the rc vertex is the *first* vertex
x_k (vertex index k >= 1, the primary hit being 0) such that the segment x_{k-1} x_k is at least
`near_distance` long, the lobe sampled at x_{k-1} was rough, and x_k is rough: for a path that
continues from x_k, the lobe it samples there is rough; for a path ending with NEE at x_k, x_k has a
rough component. Emission found by BSDF sampling can itself be the rc vertex (an "escape" vertex)
when the lobe that found it was rough and it is far enough (the environment is always far). Pure
reconnection: the rc vertex is always x_1 (x2 in the paper's numbering). Pure replay: none.

The same functions decide on the base path and, during a shift, on the destination path: the
shift is a bijection only when both sides pick the same index
(docs/theory/restir_pt.md#invertibility-and-failed-shifts).

Lobe-separated path BSDF (docs/theory/restir_pt.md#the-lobe-separated-path-bsdf): a path's
throughput at a vertex is the sampled lobe's f / p (p including the lobe-selection probability); MIS
weights use the all-lobe pdf. Only the materials with `parts` in device/bsdfs/registry.py
(roughplastic, metallic_roughness) have two smooth lobes; for every other material the two coincide.
"""
import warp as wp

from ...device.bsdf import (BSDFSample, Material, bsdf_eval_lobes, bsdf_has_rough_component, bsdf_pdf_lobes,
                            has_lobe_parts, lobe_is_rough)
from .params import SHIFT_HYBRID, SHIFT_RECONNECTION, PathReuseParams


@wp.func
def qualifies_scatter_vertex(params: PathReuseParams, k: int, dist: float, prev_rough: bool, mat: Material,
                             lobe: int) -> bool:
    """x_k, reached over a segment of length dist from x_{k-1} (whose lobe was prev_rough),
    qualifies as the rc vertex of a path that scatters on from it with `lobe`."""
    if params.shift == SHIFT_RECONNECTION:
        return k == 1
    if params.shift != SHIFT_HYBRID or k < 1:
        return False
    return dist >= params.near_distance and prev_rough and lobe_is_rough(mat, lobe, params.rough_threshold)


@wp.func
def qualifies_nee_vertex(params: PathReuseParams, k: int, dist: float, prev_rough: bool, mat: Material) -> bool:
    """x_k qualifies as the rc vertex of a path that ends with NEE at x_k."""
    if params.shift == SHIFT_RECONNECTION:
        return k == 1
    if params.shift != SHIFT_HYBRID or k < 1:
        return False
    return dist >= params.near_distance and prev_rough and bsdf_has_rough_component(mat, params.rough_threshold)


@wp.func
def qualifies_escape_vertex(params: PathReuseParams, k: int, dist: float, lobe_rough: bool, is_env: bool) -> bool:
    """The emitter (or environment) x_k found by BSDF sampling at x_{k-1} with a lobe that was
    lobe_rough qualifies as the rc vertex of the path that ends on it."""
    if params.shift == SHIFT_RECONNECTION:
        return k == 1
    if params.shift != SHIFT_HYBRID:
        return False
    return lobe_rough and (is_env or dist >= params.near_distance)


@wp.func
def lobe_weight(mat: Material, wi: wp.vec3, bs: BSDFSample) -> wp.vec3:
    """Throughput of a sampled bounce under the lobe-separated path BSDF: f_l / p_l of the lobe l
    the sample chose (the sample's own weight where the material has one smooth lobe)."""
    if bs.is_delta != 0 or not has_lobe_parts(mat):
        return bs.weight
    p = bsdf_pdf_lobes(mat, wi, bs.wo, bs.lobe)
    if p <= 0.0:
        return wp.vec3(0.0)
    return bsdf_eval_lobes(mat, wi, bs.wo, bs.lobe) / p


@wp.func
def lobe_pdf(mat: Material, wi: wp.vec3, bs: BSDFSample) -> float:
    """p_l of a sampled bounce: the density of choosing its lobe and then its direction."""
    if bs.is_delta != 0 or not has_lobe_parts(mat):
        return bs.pdf
    return bsdf_pdf_lobes(mat, wi, bs.wo, bs.lobe)


@wp.struct
class LobeEval:
    f: wp.vec3   # f_l(wi, wo) |cos|
    p: float     # p_l(wi, wo): choosing lobe l and then wo (solid angle)


@wp.func
def eval_lobe(mat: Material, wi: wp.vec3, wo: wp.vec3, lobe: int) -> LobeEval:
    """One lobe's f and pdf at a direction the shift chose (not sampled): the reconnection's."""
    e = LobeEval()
    e.f = bsdf_eval_lobes(mat, wi, wo, lobe)
    e.p = bsdf_pdf_lobes(mat, wi, wo, lobe)
    return e
