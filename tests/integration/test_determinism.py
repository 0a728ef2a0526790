"""Level 7: bitwise repeatability, and independence from how a CPU launch is sliced (R1, R2)."""
import numpy as np
import pytest

import restir


def render(slices, seed=3, device="cpu", frames=2, tracer="auto"):
    scene = restir.load_scene("builtin:cornell-box-glossy", width=24, height=20)
    cfg = restir.RenderConfig(spp=3, frames=frames, seed=seed, device=device, max_depth=6, slices=slices, tracer=tracer)
    return restir.render(scene, cfg).image


def test_same_seed_is_bitwise_identical():
    a, b = render(2), render(2)
    assert np.array_equal(a, b)


@pytest.mark.parametrize("tracer", ["auto", "warp"])
@pytest.mark.parametrize("slices", [1, 3, 7, 480])
def test_result_is_independent_of_slicing(slices, tracer):
    assert np.array_equal(render(2, tracer=tracer), render(slices, tracer=tracer))


def test_seeds_and_frames_give_independent_streams():
    a, b, c, d = (render(2, seed=s, frames=1) for s in (3, 4, 5, 6))
    assert not np.array_equal(a, b)
    # differences of independent renders are independent noise: their correlation is ~N(0, 1/n)
    x, y = (a - b).mean(-1).ravel(), (c - d).mean(-1).ravel()  # one value per pixel (channels correlate)
    assert abs(np.corrcoef(x, y)[0, 1]) < 5 / np.sqrt(x.size)


def test_cuda_matches_cpu_statistically(device):
    if device == "cpu":
        pytest.skip("run with --device cuda")
    a, b = render(None, device="cpu", frames=4), render(None, device=device, frames=4)
    assert np.abs(a.mean() - b.mean()) < 0.05 * a.mean()


def render_di(slices, mutation="none", reverse=False):
    scene = restir.load_scene("builtin:cornell-box-glossy", width=24, height=20)
    cfg = restir.RenderConfig(method="restir-di", spp=2, frames=2, seed=3, slices=slices, debug_reverse_launch=reverse,
                              settings={"candidates": 2, "spatial.rounds": 2, "spatial.neighbors": 4,
                                        "debug.mutation": mutation})
    return restir.render(scene, cfg).image


@pytest.mark.parametrize("slices", [1, 3, 7, 480])
def test_restir_di_is_independent_of_slicing(slices):
    """R2: with ping-pong buffers no pixel reads another pixel's output of the same pass."""
    assert np.array_equal(render_di(2), render_di(slices))
    assert np.array_equal(render_di(2), render_di(slices, reverse=True))  # and of the processing order


def test_in_place_spatial_output_is_caught():
    """Mutation P5/S1: writing the spatial output into the buffer the pass reads makes the
    result depend on the order pixels are processed: forward (one slice) and reversed slices
    differ, deterministically (a threaded launch would show it only when threads interleave)."""
    forward = render_di(1, "spatial_in_place")
    assert not np.array_equal(forward, render_di(7, "spatial_in_place", reverse=True))
