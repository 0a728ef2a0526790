"""The pytest helper of the harness: assert that an estimate matches a reference, and leave a
z-map image behind when it does not.

`estimate` (and `other`, the reference's result when the reference is noisy) is anything with
the batch interface the z-tests read: a RenderResult rendered with frames >= 2, or
IndependentRuns (`image`, `batch_variance_of_mean`, `batch_skewness`,
`batch_excess_kurtosis`, `frames`, and optionally `batches`).
"""
import os
import re

import numpy as np

from .stats import RGBZTest

ZMAP_DIR_ENV = "RESTIR_ZMAP_DIR"  # where failing checks write their z-maps (default out/zmaps)


def compare(estimate, reference, reference_var=0.0, *, other=None, tile=8, rel_tol=0.0, abs_tol=0.0,
            alpha=1e-3) -> RGBZTest:
    """Image, tile and pixel z-tests per channel at family-wise false-failure rate `alpha`
    (restir/validation/stats.py), with the skew and kurtosis guards of the worse side."""
    skew, kurt = np.abs(estimate.batch_skewness), estimate.batch_excess_kurtosis
    if other is not None:  # the worse of the two sides decides whether pixel statistics are normal
        skew = np.maximum(skew, np.abs(other.batch_skewness))
        kurt = np.maximum(kurt, other.batch_excess_kurtosis)
    return RGBZTest(estimate.image, estimate.batch_variance_of_mean, reference, reference_var, tile=tile,
                    alpha=alpha, df=estimate.frames - 1, skew=skew, kurtosis=kurt, rel_tol=rel_tol, abs_tol=abs_tol,
                    batches=getattr(estimate, "batches", None),
                    ref_batches=None if other is None else getattr(other, "batches", None))


def assert_matches(estimate, reference, reference_var=0.0, **kw) -> RGBZTest:
    """`compare`, printed (with its minimum detectable bias); on failure writes the z-map (see
    `zmap_path`) and raises AssertionError naming it."""
    rep = compare(estimate, reference, reference_var, **kw)
    print(rep)
    if not rep.passed:
        path = zmap_path()
        write_zmap(path, rep)
        raise AssertionError(f"{rep}\nz-map: {path}")
    return rep


def zmap_path() -> str:
    """out/zmaps/<current pytest test id>.png (or $RESTIR_ZMAP_DIR/...)."""
    test = os.environ.get("PYTEST_CURRENT_TEST", "check").split(" ")[0]
    name = re.sub(r"[^A-Za-z0-9_.-]+", "_", test).strip("_")
    return os.path.join(os.environ.get(ZMAP_DIR_ENV, os.path.join("out", "zmaps")), name + ".png")


def write_zmap(path: str, report: RGBZTest) -> None:
    from ..image_io import write_image

    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    write_image(path, report.zmap())
