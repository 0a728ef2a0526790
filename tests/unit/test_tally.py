"""The event tally (integrators/common/tally.py): device-side sums of the packed per-pixel counts
(events.py) equal numpy's int64 sums, at chunk boundaries and across several adds to one key; a read empties it."""
import numpy as np
import warp as wp

from restir.integrators.common.events import EventCounts, PassCounts, packed_counts, packed_events
from restir.integrators.common.tally import EventTally


@wp.kernel
def pack_kernel(raw: wp.array(dtype=wp.vec4i), events: wp.array(dtype=EventCounts), counts: wp.array(dtype=PassCounts)):
    i = wp.tid()
    events[i] = packed_events(raw[i])
    counts[i] = packed_counts(raw[i])


def packed(raw: np.ndarray):
    """raw (n, 4) int32 counts through the stages' own packing functions."""
    n = raw.shape[0]
    events = wp.zeros(n, dtype=EventCounts, device="cpu")
    counts = wp.zeros(n, dtype=PassCounts, device="cpu")
    wp.launch(pack_kernel, dim=n, inputs=[wp.array(raw, dtype=wp.vec4i, device="cpu")], outputs=[events, counts],
              device="cpu")
    return events, counts


def test_tally_sums_match_numpy():
    """Counts within the packed fields' range: the sums are exact, with nothing saturated."""
    wp.init()
    tally = EventTally("cpu")
    rng = np.random.default_rng(1)
    for n in (1, 255, 256, 257, 100_000):
        raw = rng.integers(0, 1000, size=(n, 4)).astype(np.int32)
        raw[:, 3] = rng.integers(0, 2 ** 31 - 1, size=n)  # rays: 32 bits in events, 16 in pass counts
        events = packed(raw)[0]
        raw_counts = raw.copy()
        raw_counts[:, 3] %= 65535
        counts = packed(raw_counts)[1]
        tally.add(("stage", n), events)
        tally.add(("stage", n), events)
        tally.add(("half", n), events, n // 2)
        tally.add(("counts", n), counts)
        got = tally.read()
        sums = raw.sum(0, dtype=np.int64)
        np.testing.assert_array_equal(got[("stage", n)], [*(2 * sums), 0])
        np.testing.assert_array_equal(got[("counts", n)], [*raw_counts.sum(0, dtype=np.int64), 0])
        if n // 2:
            np.testing.assert_array_equal(got[("half", n)], [*raw[: n // 2].sum(0, dtype=np.int64), 0])
        assert tally.read() == {}


def test_counts_saturate_and_are_reported():
    """A count past its field saturates (never wraps into another field) and is counted as such."""
    wp.init()
    tally = EventTally("cpu")
    raw = np.array([[1024, 5, 70000, 7], [3, 2000, 1, 70000], [-1, 0, 0, 0]], np.int32)
    events, counts = packed(raw)
    tally.add("e", events)
    tally.add("c", counts)
    got = tally.read()
    np.testing.assert_array_equal(got["e"], [1023 + 3, 5 + 1023, 1023 + 1, 7 + 70000, 3])
    np.testing.assert_array_equal(got["c"], [1024 + 3, 5 + 2000, 65535 + 1, 7 + 65535, 2])


def test_tally_does_not_overflow_int32():
    wp.init()
    tally = EventTally("cpu")
    raw = np.zeros((4096, 4), np.int32)
    raw[:, 3] = 2 ** 30
    tally.add("rays", packed(raw)[0])
    assert tally.read()["rays"].tolist() == [0, 0, 0, 4096 * 2 ** 30, 0]


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
