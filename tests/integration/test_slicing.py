"""Every pixel stage, launch by launch, gives bitwise the same outputs with 1 CPU slice and with
64 (R2, stage by stage). On the CPU a pixel launch runs as disjoint index ranges ("slices",
restir/parallel.py); on a GPU as one grid of concurrent threads. A stage that read what another
pixel of the same launch writes would get a result that depends on the order the pixels run in:
with slices, that shows as outputs that change with the slicing. The image-level tests
(test_determinism.py) would miss such a stage when its effect cancels or does not reach the
image; here every output buffer of every launch is compared.

The recording wraps the one launch helper every stage goes through (Integrator.run_stage and the
AOV pass call restir.parallel.launch_pixels); the stages' own kernels run unchanged.
"""
import pytest
import warp as wp

import restir
import restir.integrators.base as integrator_base
import restir.parallel as parallel

# (method, scene, max_depth, settings): every stage of each method runs, reuse of every kind with
# more than one neighbour, two frames (temporal reuse reads the first frame's outputs).
CONFIGS = [
    ("pt", "builtin:cornell-box-glossy", 4, {}),
    ("restir-di", "builtin:cornell-box-glossy", 2, {"candidates": 2, "spatial.rounds": 2, "spatial.neighbors": 4}),
    ("restir-pt", "builtin:indirect-room", 4, {"spatial.rounds": 2, "spatial.neighbors": 4}),
    ("restir-pt", "builtin:indirect-room", 4,
     {"spatial.rounds": 1, "spatial.reciprocal": False, "direct": "restir-di"}),
    ("suffix-restir", "builtin:indirect-room", 4, {"suffix.spatial.rounds": 2, "gather.suffixes": 3}),
    # the methods' settings are run-time parameters of the same kernels: other branches of them
    ("pt", "builtin:cornell-box-glossy", 4, {"strategy": "nee", "nee.samples": 2, "rr": True, "emission.rays": 4}),
    ("restir-di", "builtin:cornell-box-glossy", 2, {"temporal": False, "candidates.bsdf": 2, "spatial.rounds": 0}),
    ("restir-pt", "builtin:cornell-box-glossy", 4, {"shift": "replay", "mcmc.steps": 1, "shade.expected": True}),
    ("restir-pt", "builtin:indirect-room", 4, {"shift": "reconnection", "direct": "nee", "temporal": False}),
    ("suffix-restir", "builtin:cornell-box-glossy", 4, {"gather.mis": "pairwise", "gather.search": "hashgrid",
                                                        "direct": "restir-di"}),
    ("suffix-restir", "builtin:indirect-room", 4, {"gather.search": "bvh", "gather.canonical_per_prefix": True,
                                                   "shift": "replay"}),
    pytest.param("restir-pt", "builtin:indirect-room", 4, {"stages.split": True}, marks=pytest.mark.slow),
    pytest.param("restir-di", "builtin:cornell-box-glossy", 2, {"stages.split": True}, marks=pytest.mark.slow),
]


def contents(value) -> list:
    """The bytes of every array in a launch's output: an array, or a struct of arrays (a G-buffer;
    its scalar fields and unset arrays are passed by value, so no kernel writes them)."""
    if isinstance(value, wp.array):
        return [value.numpy().tobytes()]
    fields = getattr(getattr(value, "_cls", None), "vars", None) or {}
    return [b for name in fields for b in contents(getattr(value, name))]


def recorded_launches(monkeypatch, method, spec, max_depth, settings, slices, reverse=False):
    """[(kernel key, [each output's contents after the launch])] of one render, in launch order."""
    launches = []
    original = parallel.launch_pixels

    def recording(kernel, count, inputs, outputs, device, slices=None, reverse=False):
        original(kernel, count, inputs, outputs, device, slices, reverse)
        launches.append((kernel.key, [b for out in outputs for b in contents(out)]))

    monkeypatch.setattr(integrator_base, "launch_pixels", recording)
    monkeypatch.setattr(parallel, "launch_pixels", recording)
    scene = restir.load_scene(spec, width=24, height=20)
    cfg = restir.RenderConfig(method=method, spp=2, frames=2, seed=5, max_depth=max_depth, slices=slices,
                              debug_reverse_launch=reverse, settings=settings)
    restir.render(scene, cfg)
    monkeypatch.undo()
    return launches


@pytest.mark.parametrize("method,spec,max_depth,settings", CONFIGS)
def test_every_stage_is_independent_of_slicing(monkeypatch, method, spec, max_depth, settings):
    """64 concurrent slices, and 64 run one after another last first (a fixed order unlike one
    slice's), against one slice."""
    one = recorded_launches(monkeypatch, method, spec, max_depth, settings, slices=1)
    assert len(one) >= 2  # the recording saw the stages (both frames)
    for reverse in (False, True):
        many = recorded_launches(monkeypatch, method, spec, max_depth, settings, slices=64, reverse=reverse)
        assert [k for k, _ in one] == [k for k, _ in many]
        for i, ((kernel, a), (_, b)) in enumerate(zip(one, many)):
            assert len(a) == len(b)
            for j, (x, y) in enumerate(zip(a, b)):
                # bytes, not values: NaNs and signed zeros count, and structured arrays compare whole
                assert x == y, (f"launch {i} ({kernel}), output array {j}: differs between 1 slice and 64"
                                f"{' (last first)' if reverse else ''}")


def test_a_stage_reading_its_own_output_is_caught(monkeypatch):
    """Power: the fault injection `spatial_in_place` (ReSTIR DI's spatial pass writing the buffer it
    reads) makes some launch's outputs differ between 1 slice and 64. The 64 run one after
    another, last first (the debug order of parallel.launch_pixels), so that the order differs
    from one slice's deterministically; 64 concurrent slices differ only when threads interleave."""
    settings = {"candidates": 2, "spatial.rounds": 2, "spatial.neighbors": 4, "debug.mutation": "spatial_in_place"}
    one = recorded_launches(monkeypatch, "restir-di", "builtin:cornell-box-glossy", 2, settings, slices=1)
    many = recorded_launches(monkeypatch, "restir-di", "builtin:cornell-box-glossy", 2, settings, slices=64,
                             reverse=True)
    assert any(x != y for (_, a), (_, b) in zip(one, many) for x, y in zip(a, b))
