"""The camera's primary rays: with jitter off (RenderConfig.jitter, `--no-jitter`) every sample of a
pixel goes through its centre, for every method."""
import numpy as np
import pytest

import restir
from restir.config import RenderConfig


def _emission(jitter: bool, seed: int, method: str = "pt"):
    """What the camera sees directly (max_depth 1: emission only, so the image is a function of the
    primary rays alone)."""
    scene = restir.load_scene("builtin:cornell-box", width=24, height=24)
    return restir.render(scene, RenderConfig(method=method, spp=4, frames=1, max_depth=1, seed=seed, jitter=jitter,
                                             aovs=("normal",)))


def test_without_jitter_every_sample_sees_the_pixel_centre():
    on = [_emission(True, s) for s in (1, 2)]
    off = [_emission(False, s) for s in (1, 2)]
    # jittered: the light's edge and the box's edges land in different pixels' samples per seed
    assert not np.array_equal(on[0].image, on[1].image)
    assert not np.array_equal(on[0].aovs["normal"], on[1].aovs["normal"])
    # pixel centres: the same primary hit whatever the seed, and no variance within a pixel
    np.testing.assert_array_equal(off[0].image, off[1].image)
    np.testing.assert_array_equal(off[0].aovs["normal"], off[1].aovs["normal"])
    assert float(off[0].sample_var.max()) == 0.0
    # the light covers the same area of the image either way, up to its edge pixels
    assert abs(float(off[0].image.mean() / on[0].image.mean()) - 1.0) < 0.1


@pytest.mark.parametrize("method", ["restir-pt", "suffix-restir"])
def test_the_resampling_methods_share_the_centred_camera(method):
    """ReSTIR PT and Suffix ReSTIR trace their primary hits with the same camera: without jitter,
    their directly seen emission is the path tracer's, pixel for pixel."""
    pt = _emission(False, 3)
    other = _emission(False, 5, method)
    np.testing.assert_allclose(other.image, pt.image, rtol=1e-6, atol=0)


def test_a_mitsuba_reference_cannot_be_centred():
    from restir.compare.config import CompareConfig
    from restir.config import ConfigError

    CompareConfig(reference="mitsuba").validate()
    with pytest.raises(ConfigError, match="--no-jitter with --reference mitsuba"):
        CompareConfig(reference="mitsuba", jitter=False).validate()


def test_the_command_line_flag(tmp_path):
    from restir.cli import main

    out = tmp_path / "c.npy"
    assert main(["render", "builtin:cornell-box", "--width", "8", "--height", "8", "--spp", "2", "--max-depth", "1",
                 "--no-jitter", "--seed", "4", "--quiet", "-o", str(out)]) == 0
    np.testing.assert_array_equal(np.load(out), _emission_8x8())


def _emission_8x8():
    scene = restir.load_scene("builtin:cornell-box", width=8, height=8)
    return restir.render(scene, RenderConfig(spp=1, max_depth=1, seed=9, jitter=False)).image
