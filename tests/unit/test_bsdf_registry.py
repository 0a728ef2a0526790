"""Every material kind of device/bsdfs/registry.py is handled by the dispatch in device/bsdf.py,
and nothing is missing from the table: each MAT_* constant and each module in device/bsdfs/
has an entry (a material touches one module and one table, and this test names what else it
needs)."""
import inspect
import pkgutil

import restir.device.bsdf as bsdf
import restir.device.bsdfs as bsdfs
import restir.device.types as types
from restir.device.bsdfs.registry import MATERIAL_KINDS
from restir.scene.upload import MATERIAL_KIND


def source(fn) -> str:
    return inspect.getsource(getattr(fn, "func", fn))


def test_every_kind_is_dispatched():
    sample, lobes = source(bsdf.kind_sample), source(bsdf.kind_lobes)
    ev, pdf = source(bsdf.kind_eval), source(bsdf.kind_pdf)
    parts, smooth = source(bsdf.has_lobe_parts), source(bsdf.smooth_lobe)
    for k in MATERIAL_KINDS:
        assert k.constant in sample, f"{k.name}: kind_sample has no branch for {k.constant}"
        assert k.constant in lobes, f"{k.name}: kind_lobes has no branch for {k.constant}"
        assert (k.constant in ev) == k.smooth, f"{k.name}: kind_eval and the registry's `smooth` disagree"
        assert (k.constant in pdf) == k.smooth, f"{k.name}: kind_pdf and the registry's `smooth` disagree"
        assert (k.constant in parts) == k.parts, f"{k.name}: has_lobe_parts and the registry's `parts` disagree"
        if k.smooth and not k.parts:
            assert k.constant in smooth, f"{k.name}: smooth_lobe has no branch for {k.constant}"
        assert getattr(types, k.constant) == k.kind
        assert MATERIAL_KIND[k.name] == k.kind


def test_nothing_is_missing_from_the_table():
    constants = {n for n in dir(types) if n.startswith("MAT_")}
    assert constants == {k.constant for k in MATERIAL_KINDS}
    modules = {m.name for m in pkgutil.iter_modules(bsdfs.__path__)} - {"material", "registry"}
    assert modules == {k.module for k in MATERIAL_KINDS}
    assert len({k.kind for k in MATERIAL_KINDS}) == len(MATERIAL_KINDS)
