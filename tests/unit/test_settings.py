"""Typed method settings (restir/settings.py) as every method declares them: keys, defaults and
meanings in one place, `--set` strings parsed by the default's type, unknown keys refused, a
component's keys (di.*) reaching its nested settings, and the table `restir info` prints."""
import dataclasses

import pytest

from restir.config import ConfigError
from restir.integrators import METHODS


@pytest.mark.parametrize("name", list(METHODS))
def test_every_setting_has_a_key_default_and_meaning(name):
    cls = METHODS[name]
    assert list(cls.SETTINGS) == list(cls.Settings.defaults()) and set(cls.SETTINGS_DOC) == set(cls.SETTINGS)
    assert all(doc.strip() for doc in cls.SETTINGS_DOC.values())
    s = cls.Settings()
    for key, default in cls.SETTINGS.items():
        assert s.get(key) == default
    # the stats' table: every --set key with its value, then the render's settings
    assert list(s.as_dict())[:len(cls.SETTINGS)] == list(cls.SETTINGS)
    assert "debug.mutation" in cls.Settings.static_keys() or name == "pt"


def test_overrides_are_parsed_and_checked():
    S = METHODS["restir-pt"].Settings
    s = S.from_overrides({"candidates": "4", "temporal": "off", "temporal.cap": "2.5", "di.candidates": "3",
                          "di.visibility": "shading"}, seed=7, spp=2)
    assert (s.candidates, s.temporal, s.temporal_cap, s.seed, s.spp) == (4, False, 2.5, 7, 2)
    assert (s.di.candidates, s.di.visibility, s.di.spatial.rounds) == (3, "shading", 1)  # the path methods' DI default
    assert S().di.candidates == 8 and S().di is not S().di  # each settings object owns its component
    with pytest.raises(ConfigError, match="unknown setting 'di.debug.mutation'"):
        S.from_overrides({"di.debug.mutation": "drop_empty_neighbors"})
    with pytest.raises(ConfigError, match="unknown setting 'spatial.round'"):
        S.from_overrides({"spatial.round": "2"})
    with pytest.raises(ConfigError, match="is not an int"):
        S.from_overrides({"candidates": "four"})


def test_restir_di_defaults_and_the_path_methods_component():
    """ReSTIR DI's own defaults (docs/changelog.md#restir-di-temporalcap2-spatialrounds1-5-px) and
    those of the ReSTIR DI component of ReSTIR PT and Suffix ReSTIR, which were chosen apart and
    differ: each with the "auto" radius `restir info` documents for it."""
    S = METHODS["restir-di"].Settings
    di = S()
    assert (di.candidates, di.candidates_bsdf, di.temporal, di.temporal_cap) == (32, 1, True, 2.0)
    assert (di.spatial.rounds, di.spatial.neighbors, di.spatial.radius) == (1, 3, "auto")
    assert S().spatial.resolve_radius(128) == S().spatial.resolve_radius(1080) == 5.0
    assert S().spatial.resolve_radius(2160) == 10.0
    assert "auto: 5 px up to 1080 lines" in S.docs()["spatial.radius"]
    for method in ("restir-pt", "suffix-restir"):
        P = METHODS[method].Settings
        c = P().di
        assert (c.candidates, c.temporal_cap, c.spatial.rounds, c.spatial.neighbors) == (8, 5.0, 1, 3)
        assert P().di.spatial.resolve_radius(128) == 15.0 and P().di.spatial.resolve_radius(2160) == 30.0
        assert "auto: 15 px up to 1080 lines" in P.docs()["di.spatial.radius"]


@pytest.mark.parametrize("method", ["restir-pt", "suffix-restir"])
def test_di_settings_without_the_di_component_are_refused(method):
    """With direct=pt (ReSTIR PT's default) nothing reads the di.* settings: a changed one is
    refused, not ignored; with direct=restir-di, or at their defaults, they are accepted."""
    cls = METHODS[method]
    with pytest.raises(ConfigError, match="di.candidates set with direct=pt"):
        cls.check_settings(cls.Settings.from_overrides({"direct": "pt", "di.candidates": "16"}))
    cls.check_settings(cls.Settings.from_overrides({"direct": "restir-di", "di.candidates": "16"}))
    cls.check_settings(cls.Settings.from_overrides({"direct": "pt", "di.candidates": str(cls.Settings().di.candidates)}))


def test_the_api_gives_the_integrator_typed_settings():
    import restir
    from restir.api import make_integrator

    integ = make_integrator(restir.load_scene("builtin:cornell-box", width=8, height=8),
                            restir.RenderConfig(method="restir-di", spp=1, seed=3, settings={"candidates": "2"}))
    assert isinstance(integ.settings, METHODS["restir-di"].Settings)
    assert (integ.settings.candidates, integ.settings.seed, integ.settings.max_depth) == (2, 3, 2)
    assert dataclasses.is_dataclass(integ.settings)


@pytest.mark.parametrize("name", list(METHODS))
def test_one_mutation_registry_per_method(name):
    """Every method's fault injections in one registry (common/mutations.py): each kernel build
    returns the method's stage kernels in the shipped order with at least one of them changed;
    the pipeline mutations run the shipped kernels; debug.mutation accepts exactly its names."""
    from restir.integrators.common.mutations import Mutations

    reg = METHODS[name].MUTATIONS
    assert isinstance(reg, Mutations) and "none" in reg
    for m in reg:
        kernels = reg.kernels(m)
        assert len(kernels) == len(reg.shipped)
        changed = [a is not b for a, b in zip(kernels, reg.shipped)]
        assert any(changed) == (reg.builds[m] is not None), m
        assert reg.kernels(m) is kernels  # built once
    if name == "pt":  # the path tracer is the reference: no fault injections, no setting for them
        assert list(reg) == ["none"] and "debug.mutation" not in METHODS[name].SETTINGS
        return
    with pytest.raises(ConfigError, match="debug.mutation must be one of"):
        METHODS[name].check_settings(METHODS[name].Settings.from_overrides({"debug.mutation": "no_such_defect"}))
