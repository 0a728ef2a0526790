"""Slow tier: the Suffix ReSTIR stage matrix (docs/validation.md#level-3-stage-matrix, C5) against
the path tracer at the same
max_depth, with independent runs on both sides, on the scenes of the ReSTIR PT matrix and with its
runs per scene (test_restir_pt_matrix.py: K runs x T frames at 32x32, the path tracer's reference
rendered once per scene and camera motion; the emissive-cap sphere against its exact value).

Configurations: the final gather alone (prefix and suffix reuse off) for N in {1, 2, 4} prefixes
and M in {1, 4, 8} suffixes; prefix temporal reuse only, suffix temporal only, suffix spatial only
(each with the gather); everything (the defaults); the orbiting and dollying camera; the
reconnection and replay shifts; the ReSTIR DI component (the defaults until direct=pt); the
pairwise gather; prefixes ending exactly at x3 (non-adaptive); a canonical suffix for every
prefix; the fixed search radius; pixel-centre primary rays; the prototype's MMIS baseline with 1
and 8 suffixes per prefix; on three scenes, N = 128 prefixes (MANY_PREFIXES); on the bump-map and
mask scenes, the cells of BUMP_CELLS. Welch z per channel at image, tile and pixel level, alpha =
1e-3 per configuration, the MDB bounded per scene.
"""
import pytest

from restir.integrators.suffix_restir.pipeline import MMIS_BASELINE
from tests.helpers import FULL_MATRIX_SCENES, LIGHT_MATRIX_SCENES, MATERIAL_MATRIX_SCENES, PARTIAL_MATRIX_SCENES, run_cell

NO_REUSE = {"prefix.temporal": False, "suffix.temporal": False, "suffix.spatial.rounds": 0}
# The official prototype's direct light, the ReSTIR DI component: the default until 2026-12-06, when
# direct=pt became it (docs/changelog.md#suffix-restir-directpt). The cells that test one
# stage or option keep it, as they were validated
# (docs/validation.md#results-suffix-restir-stages-and-options); the defaults' cells (C5-all,
# -orbit, -dolly, -centre, C5-all-N128) take direct=pt, and C5-official is the old C5-all.
OFFICIAL = {"direct": "restir-di", "emission.rays": 1}
# The emission seen directly from one camera ray a sample, the default until emission.rays became
# 8 (2026-12-07): cells recorded before then keep it; C5-all, -orbit, -dolly and -centre take the
# defaults as they are.
ONE_RAY = {"emission.rays": 1}
MATRIX = {
    **{f"C5-gather-N{n}-M{m}": ({**OFFICIAL, **NO_REUSE, "gather.prefixes": n, "gather.suffixes": m}, "none")
       for n in (1, 2, 4) for m in (1, 4, 8)},
    "C5-prefix-temporal": ({**OFFICIAL, **NO_REUSE, "prefix.temporal": True}, "none"),
    "C5-suffix-temporal": ({**OFFICIAL, **NO_REUSE, "suffix.temporal": True}, "none"),
    "C5-suffix-spatial": ({**OFFICIAL, **NO_REUSE, "suffix.spatial.rounds": 1}, "none"),
    "C5-all": ({}, "none"),
    "C5-orbit": ({}, "orbit"),
    "C5-dolly": ({}, "dolly"),
    "C5-centre": ({}, "centre"),  # pixel-centre primary rays: every frame the same primary hit
    "C5-official": ({**OFFICIAL}, "none"),  # the defaults until 2026-12-06 (cell C5-all then)
    "C5-reconnection": ({**OFFICIAL, "shift": "reconnection"}, "none"),
    "C5-replay": ({**OFFICIAL, "shift": "replay"}, "none"),
    "C5-pairwise-M4": ({**OFFICIAL, "gather.mis": "pairwise", "gather.suffixes": 4}, "none"),
    "C5-prefix-exactly-x3": ({**OFFICIAL, "prefix.adaptive": False, "prefix.min_length": 2}, "none"),
    "C5-canonical-each": ({**OFFICIAL, "gather.canonical_per_prefix": True}, "none"),
    "C5-radius-fixed": ({**OFFICIAL, "gather.radius_type": "fixed"}, "none"),
    # the official prototype's MMIS baseline (MMIS_BASELINE): fresh suffixes gathered by MIS, no reuse
    "C5-mmis-M1": ({**OFFICIAL, **MMIS_BASELINE}, "none"),
    "C5-mmis-M8": ({**OFFICIAL, **MMIS_BASELINE, "gather.suffixes": 8}, "none"),
}


# on the bump-map and the mask scenes (shifts across tilted frames and null lobes): the gather alone, each reuse, the shifts and a moving camera
BUMP_CELLS = ["C5-gather-N2-M4", "C5-prefix-temporal", "C5-suffix-spatial", "C5-all", "C5-reconnection", "C5-replay",
              "C5-orbit"]


@pytest.mark.slow
@pytest.mark.parametrize("config", list(MATRIX))
@pytest.mark.parametrize("name", FULL_MATRIX_SCENES)
def test_suffix_restir_matrix(name, config):
    settings, motion = MATRIX[config]
    print(config, end=" ")
    run_cell(name, "suffix-restir", settings, motion, config)


# N = 128 gathered prefixes, the paper's largest, with every reuse on: on the scenes where a cell
# costs minutes (at 32x32 a frame traces about 1,500 gather rays a pixel)
MANY_PREFIXES = {"C5-all-N128": ({"gather.prefixes": 128, **ONE_RAY}, "none")}


@pytest.mark.slow
@pytest.mark.parametrize("config", list(MANY_PREFIXES))
@pytest.mark.parametrize("name", ["sphere-cap", "cornell-box-glossy", "indirect-room"])
def test_suffix_restir_matrix_many_prefixes(name, config):
    settings, motion = MANY_PREFIXES[config]
    print(config, end=" ")
    run_cell(name, "suffix-restir", settings, motion, config)


@pytest.mark.slow
@pytest.mark.parametrize("config", BUMP_CELLS)
@pytest.mark.parametrize("name", PARTIAL_MATRIX_SCENES)
def test_suffix_restir_matrix_on_bump_maps_and_masks(name, config):
    settings, motion = MATRIX[config]
    print(config, end=" ")
    run_cell(name, "suffix-restir", settings, motion, config)


# on the delta-light and thin-lens scenes (tests/helpers.py LIGHT_MATRIX_SCENES): the gather alone,
# each reuse, the shifts, the defaults still and moving
LIGHT_CELLS = ["C5-gather-N2-M4", "C5-prefix-temporal", "C5-suffix-temporal", "C5-suffix-spatial", "C5-all",
               "C5-reconnection", "C5-orbit"]


@pytest.mark.slow
@pytest.mark.parametrize("config", LIGHT_CELLS)
@pytest.mark.parametrize("name", LIGHT_MATRIX_SCENES + MATERIAL_MATRIX_SCENES)
def test_suffix_restir_matrix_on_delta_lights_and_a_lens(name, config):
    settings, motion = MATRIX[config]
    print(config, end=" ")
    run_cell(name, "suffix-restir", settings, motion, config)
