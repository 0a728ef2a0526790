"""ReSTIR DI against the direct-only path tracer (`--method pt --max-depth 2`), per pixel.

Both sides noisy: Welch z per channel over 32 frames (batch means), alpha = 1e-3 per
configuration, image/tile/pixel levels as tests/stats.py; the MDB is asserted small.
This commit covers the canonical (initial RIS) stage; reuse stages add their configurations.
"""
import pytest

import restir
from tests.integration.test_path_tracer import check

FRAMES = 32


def scene_for(name, tmp_path):
    if name == "features":
        from tests.data.feature_scene import write_feature_scene

        return restir.load_scene(write_feature_scene(str(tmp_path)))
    return restir.load_scene(f"builtin:{name}")


def render(scene, method, spp, seed, **settings):
    cfg = restir.RenderConfig(method=method, spp=spp, frames=FRAMES, width=24, height=24, seed=seed,
                              max_depth=2, settings=settings)
    return restir.render(scene, cfg)


# (DI spp, PT spp, MDB bound): in the Cornell boxes the pixels on the edge of the small, bright
# light dominate the image-level variance of both sides.
SAMPLES = {"cornell-box": (32, 128, 0.05), "cornell-box-glossy": (32, 128, 0.05), "features": (8, 32, 0.03)}


@pytest.mark.parametrize("candidates", [1, 4, 32])
@pytest.mark.parametrize("name", list(SAMPLES))
def test_canonical_matches_direct_path_tracing(name, candidates, tmp_path):
    scene = scene_for(name, tmp_path)
    spp_di, spp_pt, bound = SAMPLES[name]
    di = render(scene, "restir-di", spp_di, seed=3, candidates=candidates)
    pt = render(scene, "pt", spp_pt, seed=4)
    print(name, f"candidates={candidates}")
    rep = check(di, pt.image, pt.batch_variance_of_mean, other=pt, tile=4)
    assert rep.mdb < bound
