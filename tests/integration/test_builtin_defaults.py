"""The analytic builtins (furnace, sphere-cap) render at a bounded default depth (Russian roulette
is off, so unbounded depth means 1023 bounces per path); an explicit max_depth still wins,
-1 included, and a default render matches the analytic value for the default depth."""
import time

import pytest

import restir
from restir.scene.builtin import ANALYTIC_MAX_DEPTH, BUILTIN_DESCRIPTIONS, sphere_cap_radiance
from tests.helpers import ANALYTIC_REL_TOL, check


@pytest.mark.parametrize("name", ["furnace", "sphere-cap"])
def test_default_depth_is_bounded_and_stated(name):
    assert ANALYTIC_MAX_DEPTH == 64
    assert restir.load_scene(f"builtin:{name}").max_depth == 64
    assert restir.load_scene(f"builtin:{name}", max_depth=-1).max_depth == -1  # explicit: unbounded
    assert restir.load_scene(f"builtin:{name}", max_depth=3).max_depth == 3
    assert "max_depth 64" in BUILTIN_DESCRIPTIONS[name]


@pytest.mark.parametrize("name,expected", [("furnace", 1 - 0.5 ** 64),
                                           ("sphere-cap", sphere_cap_radiance(0.5, 1.0, 0.05, 64))])
def test_default_render_matches_the_analytic_value(device, name, expected):
    scene = restir.load_scene(f"builtin:{name}", width=8, height=8)
    t0 = time.perf_counter()
    r = restir.render(scene, restir.RenderConfig(spp=4, frames=16, device=device))
    assert r.stats["max_depth"] == 64
    assert check(r, expected, rel_tol=ANALYTIC_REL_TOL).mdb < 0.05
    print(f"{name}: {time.perf_counter() - t0:.2f} s")
