"""The unbiasedness harness (TESTING.md 5.1-5.2): independent runs, per-pixel statistics,
image / tile / pixel z-tests with Bonferroni splits, skew and kurtosis guards, minimum
detectable bias. Used by `restir validate` and by the test suite
(`assert_matches`, the pytest helper, writes a z-map of a failing check)."""
from .check import assert_matches
from .runs import DEFAULT_MAX_MDB, IndependentRuns, Validation, validate
from .stats import RGBZTest, ZTestReport

__all__ = ["IndependentRuns", "Validation", "DEFAULT_MAX_MDB", "validate", "assert_matches", "RGBZTest", "ZTestReport"]
