"""The event tally (integrators/common/tally.py): device-side sums of per-pixel vec4i events equal
numpy's int64 sums, at chunk boundaries and across several adds to one key; a read empties it."""
import numpy as np
import warp as wp

from restir.integrators.common.tally import EventTally


def test_tally_sums_match_numpy():
    wp.init()
    tally = EventTally("cpu")
    rng = np.random.default_rng(1)
    for n in (1, 255, 256, 257, 100_000):
        ev = rng.integers(-5, 1000, size=(n, 4)).astype(np.int32)
        a = wp.array(ev, dtype=wp.vec4i, device="cpu")
        tally.add(("stage", n), a)
        tally.add(("stage", n), a)
        tally.add(("half", n), a, n // 2)
        got = tally.read()
        np.testing.assert_array_equal(got[("stage", n)], 2 * ev.sum(0, dtype=np.int64))
        if n // 2:
            np.testing.assert_array_equal(got[("half", n)], ev[: n // 2].sum(0, dtype=np.int64))
        assert tally.read() == {}


def test_tally_does_not_overflow_int32():
    wp.init()
    tally = EventTally("cpu")
    big = wp.array(np.full((4096, 4), 2 ** 30, np.int32), dtype=wp.vec4i, device="cpu")
    tally.add("rays", big)
    assert tally.read()["rays"].tolist() == [4096 * 2 ** 30] * 4


def test_sample_film_matches_pixel_moments():
    """The device film (film.py) against the host's PixelMoments, the accumulation it replaced:
    the mean bit for bit (float32), the variance to float64 rounding; one sample is itself."""
    from types import SimpleNamespace

    from restir.film import PixelMoments, SampleFilm

    wp.init()
    rng = np.random.default_rng(2)
    n, shape = 300, (10, 30, 3)
    for spp in (1, 2, 5):
        buffers = []
        integ = SimpleNamespace(num_pixels=n, device="cpu",
                                buffer=lambda name, dtype: buffers.append(name) or wp.zeros(n, dtype=dtype, device="cpu"))
        film, host = SampleFilm(integ, spp), PixelMoments((n, 3))
        for frame in range(2):  # a second frame starts over
            film.begin()
            host = PixelMoments((n, 3))
            for _ in range(spp):
                x = (rng.standard_normal((n, 3)) * 10 ** rng.uniform(-3, 3)).astype(np.float32)
                film.add(wp.array(x, dtype=wp.vec3, device="cpu"))
                host.add(x)
            mean, var = film.read(shape)
            np.testing.assert_array_equal(mean, host.mean.reshape(shape).astype(np.float32))
            np.testing.assert_allclose(var, host.variance.reshape(shape), rtol=1e-12, atol=0)
        assert buffers == ([] if spp == 1 else ["film_mean", "film_m2"])
