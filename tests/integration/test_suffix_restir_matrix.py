"""Slow tier: the Suffix ReSTIR stage matrix (TESTING.md 5.6, C5) against the path tracer at the same
max_depth, with independent runs on both sides, on the scenes of the ReSTIR PT matrix and with its
runs per scene (test_restir_pt_matrix.py: K runs x T frames at 32x32, the path tracer's reference
rendered once per scene and camera motion; the emissive-cap sphere against its exact value).

Configurations: the final gather alone (prefix and suffix reuse off) for N in {1, 2, 4} prefixes
and M in {1, 4, 8} suffixes; prefix temporal reuse only, suffix temporal only, suffix spatial only
(each with the gather); everything (the defaults); the orbiting and dollying camera; the
reconnection and replay shifts; direct=pt; the pairwise gather; prefixes ending exactly at x3
(non-adaptive); a canonical suffix for every prefix; the fixed search radius; pixel-centre
primary rays; the prototype's MMIS baseline with 1 and 8 suffixes per prefix; on three scenes, N = 128 prefixes (MANY_PREFIXES); on the bump-map and mask
scenes, the cells of BUMP_CELLS. Welch z per channel at image,
tile and pixel level, alpha = 1e-3 per configuration, the MDB bounded per scene.
"""
import pytest

from restir.integrators.suffix_restir.pipeline import MMIS_BASELINE
from tests.helpers import FULL_MATRIX_SCENES, PARTIAL_MATRIX_SCENES, run_cell

NO_REUSE = {"prefix.temporal": False, "suffix.temporal": False, "suffix.spatial.rounds": 0}
MATRIX = {
    **{f"C5-gather-N{n}-M{m}": ({**NO_REUSE, "gather.prefixes": n, "gather.suffixes": m}, "none")
       for n in (1, 2, 4) for m in (1, 4, 8)},
    "C5-prefix-temporal": ({**NO_REUSE, "prefix.temporal": True}, "none"),
    "C5-suffix-temporal": ({**NO_REUSE, "suffix.temporal": True}, "none"),
    "C5-suffix-spatial": ({**NO_REUSE, "suffix.spatial.rounds": 1}, "none"),
    "C5-all": ({}, "none"),
    "C5-orbit": ({}, "orbit"),
    "C5-dolly": ({}, "dolly"),
    "C5-centre": ({}, "centre"),  # pixel-centre primary rays: every frame the same primary hit
    "C5-reconnection": ({"shift": "reconnection"}, "none"),
    "C5-replay": ({"shift": "replay"}, "none"),
    "C5-direct-pt": ({"direct": "pt"}, "none"),
    "C5-pairwise-M4": ({"gather.mis": "pairwise", "gather.suffixes": 4}, "none"),
    "C5-prefix-exactly-x3": ({"prefix.adaptive": False, "prefix.min_length": 2}, "none"),
    "C5-canonical-each": ({"gather.canonical_per_prefix": True}, "none"),
    "C5-radius-fixed": ({"gather.radius_type": "fixed"}, "none"),
    # the official prototype's MMIS baseline (MMIS_BASELINE): fresh suffixes gathered by MIS, no reuse
    "C5-mmis-M1": (MMIS_BASELINE, "none"),
    "C5-mmis-M8": ({**MMIS_BASELINE, "gather.suffixes": 8}, "none"),
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
MANY_PREFIXES = {"C5-all-N128": ({"gather.prefixes": 128}, "none")}


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
