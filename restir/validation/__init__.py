"""The unbiasedness harness: independent runs, per-pixel statistics, image / tile / pixel
z-tests with Bonferroni splits, skew and kurtosis guards, minimum detectable bias
(docs/validation.md#harness-rules, docs/validation.md#statistical-machinery). Used by
`restir validate` and by the test suite (`assert_matches`, the pytest helper, writes a z-map of
a failing check)."""
from .check import assert_matches
from .runs import DEFAULT_MAX_MDB, ImageBatches, IndependentRuns, Validation, validate, validate_images
from .stats import RGBZTest, ZTestReport

__all__ = ["ImageBatches", "validate_images", "IndependentRuns", "Validation", "DEFAULT_MAX_MDB", "validate", "assert_matches", "RGBZTest", "ZTestReport"]
