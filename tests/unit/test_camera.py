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


# ----------------------------------------------------------------------------- emission.rays
def _emission_by_quadrature(scene, points: int = 46368) -> np.ndarray:
    """The expected emission seen directly per pixel (max_depth 1), by quadrature over the camera's
    two numbers with the stage's own functions (generate_ray, trace_closest, emission_seen): a
    Fibonacci lattice of F_k points, whose projections on both axes are the full F_k-point grid, so
    the light's axis-aligned edges are integrated to 1/F_k of their pixels' values."""
    import warp as wp

    from restir.device.camera import Camera, generate_ray
    from restir.device.intersect import T_MAX, trace_closest
    from restir.device.scene_device import SceneDevice
    from restir.integrators.common.primary_hits import emission_seen
    from restir.scene.upload import DeviceScene

    @wp.kernel
    def quadrature(scene: SceneDevice, cam: Camera, n: int, generator: int, out: wp.array(dtype=wp.vec3)):
        pixel = wp.tid()
        acc = wp.vec3(0.0)
        for a in range(n):
            u = wp.vec2((float(a) + 0.5) / float(n), (float((a * generator) % n) + 0.5) / float(n))
            r = generate_ray(cam, pixel % cam.width, pixel // cam.width, u, wp.vec2(0.5))
            acc += emission_seen(scene, trace_closest(scene, r.o, r.d, T_MAX), r.d) * r.weight
        out[pixel] = acc / float(n)

    ds = DeviceScene(scene, "cpu")
    cam = scene.camera
    out = wp.zeros(cam.width * cam.height, dtype=wp.vec3)
    wp.launch(quadrature, dim=out.shape[0], inputs=[ds.scene, ds.camera, points, 28657], outputs=[out])  # F_24, F_23
    return out.numpy().astype(np.float64).reshape(cam.height, cam.width, 3)


def _z_against_quadrature(scene, r) -> tuple:
    """z of the render's image mean against the quadrature, and its standard error."""
    expected = _emission_by_quadrature(scene)
    se = float(np.sqrt(r.variance_of_mean.sum())) / expected.size
    return (float(r.image.mean()) - float(expected.mean())) / se, se


@pytest.mark.parametrize("method,spp,frames,adaptive", [("pt", 16384, 1, False), ("restir-pt", 512, 8, False),
                                                        ("pt", 2048, 8, True), ("restir-pt", 512, 8, True)])
def test_emission_rays_estimate_the_emission_seen_directly(method, spp, frames, adaptive):
    """emission.rays = 4: the emission seen directly is the mean over the sample's camera ray and
    three more on a lattice shifted by its position, through the path tracer's kernel and the
    primary-hit stage of the other methods; at every pixel, or (emission.adaptive) only where the
    previous launch saw the emission vary nearby. The image at max_depth 1 (emission alone) must
    match the quadrature: |z| < 4 on the image mean (false failure about 6e-5; the standard error,
    from the samples' variance, is below 0.3% of the mean, so a bias of 1.2% is found). And the
    emitter's edge, one ray a sample before, must be less noisy per sample."""
    scene = restir.load_scene("builtin:cornell-box", width=16, height=16)
    runs = {n: restir.render(scene, RenderConfig(method=method, spp=spp, frames=frames, max_depth=1, seed=11,
                                                 settings={"emission.rays": str(n),
                                                           "emission.adaptive": str(adaptive).lower()}))
            for n in (1, 4)}
    r = runs[4]
    z, se = _z_against_quadrature(scene, r)
    assert abs(z) < 4.0, z
    assert se < 0.003 * float(r.image.mean())
    assert float(r.sample_var.sum()) < 0.5 * float(runs[1].sample_var.sum())
    stage = "path_trace" if method == "pt" else "gbuffer"
    rays, one = r.stats["rays_by_stage"][stage], runs[1].stats["rays_by_stage"][stage]
    assert one == 256 * spp * frames
    if not adaptive:  # four rays a sample, where one was traced
        assert rays == 4 * one
    else:  # four at the light's edge (and everywhere in the first launch), one elsewhere
        first_launch = 4 * 256 * (spp if method == "pt" else 1)
        assert one < rays - first_launch < 0.5 * 4 * one, rays / one


def test_emission_rays_is_refused_out_of_range():
    from restir.config import ConfigError

    scene = restir.load_scene("builtin:cornell-box", width=8, height=8)
    for bad in ("0", "65"):
        with pytest.raises(ConfigError, match=r"emission.rays must be in \[1, 64\]"):
            restir.render(scene, RenderConfig(method="restir-pt", settings={"emission.rays": bad}))


@pytest.mark.parametrize("mutation,settings", [
    ("emission_lattice_fixed", {"emission.adaptive": "false"}),
    ("emission_rays_by_own_ray", {})])
def test_the_emission_rays_mutations_are_caught(mutation, settings):
    """The mutations of emission.rays (docs/validation.md#power-checks-the-mutation-table), which
    the test above must fail:
    emission_lattice_fixed, the extra rays at the lattice's points not shifted by the sample's
    position, so each always samples the same spot of the pixel (measured: z = -244); and
    emission_rays_by_own_ray, the four rays traced where the sample's own ray saw the light rather
    than where the previous launch saw the emission vary: a choice made from the estimate it
    scales, biased low at the light's edge (measured: z = -193)."""
    scene = restir.load_scene("builtin:cornell-box", width=16, height=16)
    r = restir.render(scene, RenderConfig(method="restir-pt", spp=512, frames=8, max_depth=1, seed=11,
                                          settings={"emission.rays": "4", "debug.mutation": mutation, **settings}))
    z, _ = _z_against_quadrature(scene, r)
    assert abs(z) > 20.0, z


def test_emission_rays_without_jitter_trace_one_ray():
    """With pixel-centre rays every one of the emission.rays would be the sample's own: one is
    traced, and the image is the one-ray image bit for bit."""
    for method in ("pt", "restir-pt"):
        one, four = (_render_centred(method, n) for n in (1, 4))
        np.testing.assert_array_equal(one.image, four.image)
        stage = "path_trace" if method == "pt" else "gbuffer"
        assert four.stats["rays_by_stage"][stage] == one.stats["rays_by_stage"][stage] == 8 * 8 * 2


def _render_centred(method, n):
    scene = restir.load_scene("builtin:cornell-box", width=8, height=8)
    return restir.render(scene, RenderConfig(method=method, spp=2, frames=1, max_depth=1, seed=4, jitter=False,
                                             settings={"emission.rays": str(n)}))


def test_adaptive_emission_rays_keep_the_image_with_fewer_rays():
    """emission.adaptive (the default) traces the extra rays only where the previous launch saw
    the emission vary in a pixel's 3x3 neighbourhood. On the glossy box, still and orbiting, that
    neighbourhood holds every pixel the light's edge crosses, and elsewhere all rays see the same
    emission: the images are those of the rays at every pixel, bit for bit (measured; an edge
    that moved more than a pixel between launches would change them, without bias), at less than
    half the camera rays after the first launch (which traces them everywhere)."""
    scene = restir.load_scene("builtin:cornell-box-glossy", width=24, height=20)
    for motion in ("none", "orbit"):
        runs = {a: restir.render(scene, RenderConfig(method="restir-pt", spp=2, frames=3, seed=5, camera_motion=motion,
                                                     camera_speed=2.0, settings={"emission.adaptive": a}))
                for a in ("true", "false")}
        np.testing.assert_array_equal(runs["true"].image, runs["false"].image)
        rays = {a: r.stats["rays_by_stage"]["gbuffer"] for a, r in runs.items()}
        first_launch = 4 * 24 * 20
        assert rays["false"] == 4 * 24 * 20 * 6
        assert rays["true"] - first_launch < 0.5 * (rays["false"] - first_launch), rays
