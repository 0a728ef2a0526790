"""The equal-time baseline the benchmarks read without rounding (benchmarks/bench_error_structure.py,
`pt_between`): a method's frame time as path-tracer spp on the line through the path tracer's own
frames, its denoised error there interpolated log-log between the neighbouring spp."""
import math

import pytest

from benchmarks.bench_error_structure import pt_between


def rows(*methods):
    return [{"method": m, "ms_per_frame": t, "relmse_denoised_frame": e} for m, t, e in methods]


def test_frame_time_between_two_spp_interpolates_log_log():
    # the path tracer: 10 ms fixed + 30 ms a sample; error 0.04 at 1 spp, 0.02 at 2
    out = pt_between(rows(("pt", 40.0, 0.04), ("pt:spp=2", 70.0, 0.02), ("restir-pt", 55.0, 0.025)))
    spp, e, f = out["restir-pt"]
    assert spp == pytest.approx(1.5)
    t = math.log(1.5) / math.log(2.0)
    assert e == pytest.approx(math.exp((1 - t) * math.log(0.04) + t * math.log(0.02)))
    assert f == pytest.approx(e / 0.025)
    assert 0.02 < e < 0.04


def test_outside_the_path_tracers_spp_extrapolates_from_the_nearest_two():
    out = pt_between(rows(("pt", 40.0, 0.04), ("pt:spp=2", 70.0, 0.02), ("pt:spp=3", 100.0, 0.0135),
                          ("suffix-restir", 160.0, 0.01)))
    spp, e, _ = out["suffix-restir"]
    assert spp == pytest.approx(5.0)
    t = (math.log(5.0) - math.log(2.0)) / (math.log(3.0) - math.log(2.0))
    assert e == pytest.approx(math.exp((1 - t) * math.log(0.02) + t * math.log(0.0135)))


def test_a_frame_cheaper_than_one_sample_is_one_sample_and_pt_rows_get_none():
    out = pt_between(rows(("pt", 40.0, 0.04), ("pt:spp=2", 70.0, 0.02), ("restir-pt", 20.0, 0.05)))
    assert set(out) == {"restir-pt"}
    assert out["restir-pt"][0] == 1.0
    assert out["restir-pt"][1] == pytest.approx(0.04)


def test_one_path_tracer_row_gives_no_baseline():
    assert pt_between(rows(("pt", 40.0, 0.04), ("restir-pt", 55.0, 0.025))) == {}
