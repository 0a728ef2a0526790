"""The material kinds, one entry each: the scene's name for it, its MAT_* constant, its module
in bsdfs/, and what the dispatch in device/bsdf.py must hold for it. A new material is a module
here and one line in this table; tests/unit/test_bsdf_registry.py checks that bsdf.py's
dispatch handles every entry (and that no module or constant is missing from the table).

- `smooth`: the kind has a non-delta lobe, so `kind_eval` and `kind_pdf` call it;
- `parts`: more than one non-delta lobe on a side, so `bsdf_eval_lobes` and `bsdf_pdf_lobes`
  call its lobe-restricted `*_parts` functions (ReSTIR PT's lobe-separated path BSDF); a kind
  without parts has its one smooth lobe in `smooth_lobe`.
"""
from dataclasses import dataclass

from ..types import (MAT_CONDUCTOR, MAT_DIELECTRIC, MAT_DIFFUSE, MAT_DIFFUSE_TRANSMISSION, MAT_METALLIC_ROUGHNESS, MAT_PLASTIC,
                     MAT_ROUGHCONDUCTOR, MAT_ROUGHDIELECTRIC, MAT_ROUGHPLASTIC, MAT_THINDIELECTRIC)


@dataclass(frozen=True)
class MaterialKind:
    name: str          # the scene's type (Mitsuba's plugin name, or restir's for other formats')
    kind: int          # its MAT_* constant (types.py)
    constant: str      # that constant's name, as bsdf.py's dispatch spells it
    module: str        # bsdfs/<module>.py
    smooth: bool       # has a non-delta lobe
    parts: bool        # has several non-delta lobes: lobe-restricted eval and pdf


MATERIAL_KINDS = (
    MaterialKind("diffuse", int(MAT_DIFFUSE), "MAT_DIFFUSE", "diffuse", True, False),
    MaterialKind("conductor", int(MAT_CONDUCTOR), "MAT_CONDUCTOR", "conductor", False, False),
    MaterialKind("roughconductor", int(MAT_ROUGHCONDUCTOR), "MAT_ROUGHCONDUCTOR", "conductor", True, False),
    MaterialKind("dielectric", int(MAT_DIELECTRIC), "MAT_DIELECTRIC", "dielectric", False, False),
    MaterialKind("thindielectric", int(MAT_THINDIELECTRIC), "MAT_THINDIELECTRIC", "dielectric", False, False),
    MaterialKind("roughdielectric", int(MAT_ROUGHDIELECTRIC), "MAT_ROUGHDIELECTRIC", "dielectric", True, False),
    MaterialKind("plastic", int(MAT_PLASTIC), "MAT_PLASTIC", "plastic", True, False),
    MaterialKind("roughplastic", int(MAT_ROUGHPLASTIC), "MAT_ROUGHPLASTIC", "plastic", True, True),
    MaterialKind("metallic_roughness", int(MAT_METALLIC_ROUGHNESS), "MAT_METALLIC_ROUGHNESS", "metallic_roughness",
                 True, True),
    # one non-delta lobe on each side: wo's side says which (smooth_lobe)
    MaterialKind("diffuse_transmission", int(MAT_DIFFUSE_TRANSMISSION), "MAT_DIFFUSE_TRANSMISSION",
                 "diffuse_transmission", True, False),
)
