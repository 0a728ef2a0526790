"""`restir validate`'s verdict: a pass needs a minimum detectable bias at or below the stated
bound; above it the verdict is inconclusive, with the runs that would bring the MDB there."""
import math

import pytest

from restir.validation.runs import DEFAULT_MAX_MDB, Validation


class Report:
    def __init__(self, passed=True, mdb=0.01, conclusive=True, tiles_conclusive=True):
        self.passed, self.mdb = passed, mdb
        self.reports = [type("R", (), {"pixel_conclusive": conclusive, "tile_conclusive": tiles_conclusive})()] * 3


class Runs:
    def __init__(self, runs):
        self.frames = runs


def test_default_bound_is_five_percent():
    from restir import cli

    assert DEFAULT_MAX_MDB == 0.05 and cli.fraction(cli.DEFAULT_MAX_MDB) == DEFAULT_MAX_MDB
    assert cli.fraction("0.05") == cli.fraction("5%") == 0.05


@pytest.mark.parametrize("mdb,verdict", [(0.01, "pass"), (0.05, "pass"), (0.0501, "inconclusive"),
                                         (1.04, "inconclusive"), (math.inf, "inconclusive"),
                                         (math.nan, "inconclusive")])
def test_pass_needs_a_small_enough_mdb(mdb, verdict):
    assert Validation(Report(mdb=mdb), Runs(8), Runs(8)).verdict == verdict


def test_a_detected_bias_fails_whatever_the_mdb():
    assert Validation(Report(passed=False, mdb=1.04), Runs(8), Runs(8)).verdict == "fail"


def test_skewed_pixels_stay_inconclusive():
    assert Validation(Report(mdb=0.01, conclusive=False), Runs(8), Runs(8)).verdict == "inconclusive"


def test_runs_needed():
    """MDB scales as 1/sqrt(runs): runs * (mdb / bound)^2, rounded up."""
    v = Validation(Report(mdb=1.04), Runs(8), Runs(8))
    assert v.runs_needed == math.ceil(8 * (1.04 / 0.05) ** 2) == 3462
    assert Validation(Report(mdb=0.1), Runs(32), Runs(32), max_mdb=0.02).runs_needed == 800
    assert Validation(Report(mdb=0.01), Runs(32), Runs(32)).runs_needed == 32  # already enough
    assert Validation(Report(mdb=math.inf), Runs(8), Runs(8)).runs_needed is None
    assert "3462 runs" in Validation(Report(mdb=1.04), Runs(8), Runs(8)).reason


def test_skewed_tiles_stay_inconclusive():
    v = Validation(Report(mdb=0.01, tiles_conclusive=False), Runs(8), Runs(8))
    assert v.verdict == "inconclusive" and "tile" in v.reason
