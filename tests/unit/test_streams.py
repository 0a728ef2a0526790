"""No two stages share a random stream, and no two uses inside a stage share a dimension
(restir/device/streams.py). Two uses of one (stage, dim) would correlate decisions that the
estimators assume independent, which biases nothing visibly but breaks every variance argument."""
from restir.device import streams


def test_stage_id_ranges_are_disjoint():
    owner = {}
    for name, first, count in streams.STAGE_RANGES:
        assert count >= 1
        for sid in range(first, first + count):
            assert sid not in owner, f"stage id {sid} used by {owner[sid]} and {name}"
            owner[sid] = name
    # the settings that index into ranges cannot leave them
    assert streams.MAX_SPATIAL_ROUNDS <= dict((n, c) for n, _, c in streams.STAGE_RANGES)["di_spatial"]


def test_dimension_layouts_fit_and_do_not_overlap():
    assert {n for n, _, _ in streams.DIM_LAYOUTS} <= {n for n, _, _ in streams.STAGE_RANGES}
    for name, per_sample, uses in streams.DIM_LAYOUTS:
        taken = set()
        for first, count in uses:
            dims = set(range(first, first + count))
            assert not dims & taken, f"{name}: dimensions {sorted(dims & taken)[:4]} used twice"
            assert first >= 0 and first + count <= per_sample, f"{name}: use at {first} leaves its sample's block"
            taken |= dims
    assert streams.DI_MAX_CANDIDATES * streams.DI_DIMS_PER_CANDIDATE <= streams.DIMS_PER_SAMPLE
    assert (streams.MAX_SEGMENTS + 1) * streams.DIMS_PER_BOUNCE <= streams.DIMS_PER_SAMPLE
