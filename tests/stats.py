"""The statistics live in the package (restir/validation/stats.py) so `restir validate` uses
the same machinery as the test suite; re-exported here for the tests."""
from restir.validation.stats import *  # noqa: F401,F403
from restir.validation.stats import RGBZTest, ZTestReport, chi2_test, expected_counts, histogram_directions  # noqa: F401
from restir.validation.stats import integration_points, mdb, skewness, tile_means, z_threshold  # noqa: F401
