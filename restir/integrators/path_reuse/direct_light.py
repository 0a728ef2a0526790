"""ReSTIR DI as the direct-light component of a path-reuse method (ReSTIR PT, Suffix ReSTIR).

With `direct=restir-di` such a method leaves the events at the primary hit (its emission, direct
light, delta bounces to an emitter) to ReSTIR DI, run on the method's own primary-hit layer (its
G-buffers, filter weights and emission), with its stage times, counters and buffers reported
under "di.". Its settings are the method's `di.*` settings.

The component has defaults of its own, not ReSTIR DI's: 8 light candidates and 1 spatial round,
measured at equal time on the indirect room, veach-bidir and the glossy box
(docs/changelog.md#restir-pts-restir-di-component-8-candidates-1-round): they leave ReSTIR PT's
error unchanged (within 0.3%) against 32 candidates and 2 rounds, and its frame 17-33% cheaper,
since the direct light's share of the error is small beside the indirect paths' and the one
camera sample's. Its history cap (5) and spatial radius (15 px up to 1080 lines) are those ReSTIR
PT's and Suffix ReSTIR's measurements ran with; ReSTIR DI's own (cap 2, 5 px) were chosen for
ReSTIR DI alone (docs/changelog.md#restir-di-temporalcap2-spatialrounds1-5-px).
"""
import copy
import dataclasses

from ...settings import component
from ..common.spatial_settings import SpatialReuseSettings, spatial_reuse
from ..restir_di.pipeline import DISettings, ReSTIRDI


@dataclasses.dataclass
class ComponentDISettings(DISettings):
    """ReSTIR DI's settings as a path method's component: its own spatial radius (15 px up to 1080
    lines, which `restir info` prints for di.spatial.radius) and 1 round; the other defaults that
    differ from ReSTIR DI's are set by `di_component`."""
    spatial: SpatialReuseSettings = spatial_reuse("spatial.", radius_at_1080=15.0, rounds=1)


def di_component():
    """The `di.*` settings field of a path-reuse method's settings: ReSTIR DI's, with the
    component's defaults above (8 candidates, history cap 5, 1 spatial round in 15 px), without its
    fault injection."""
    return component("di.", _path_method_di_defaults, "ReSTIR DI's ",
                     exclude=("debug.mutation", "emission.rays", "emission.adaptive"))


def _path_method_di_defaults() -> DISettings:
    return ComponentDISettings(candidates=8, temporal_cap=5.0)


def di_settings(settings) -> DISettings:
    """ReSTIR DI's settings from a path method's: its di.* settings and the shared render settings."""
    render = {**settings.render_settings(), "max_depth": 2}
    # a copy, nested groups included: ReSTIR DI writes its resolved radius into its own settings
    return dataclasses.replace(copy.deepcopy(settings.di), **render, debug_mutation="none")


def check_di_settings(settings) -> None:
    """The component's settings, as ReSTIR DI checks its own. With direct=pt there is no
    component, so a di.* setting changed from its default would be ignored: refused instead."""
    from ...config import ConfigError

    if settings.direct != "restir-di":
        changed = [key for key, _, default, _, _ in type(settings).entries()
                   if key.startswith("di.") and settings.get(key) != default]
        if changed:
            raise ConfigError(f"{', '.join(changed)} set with direct={settings.direct}, which takes no direct light "
                              "from ReSTIR DI: add direct=restir-di, or leave the di.* settings at their defaults")
    ReSTIRDI.check_settings(di_settings(settings))


def attach_direct_light(integ) -> ReSTIRDI | None:
    """The ReSTIR DI component of `integ` (which has allocated `gbuffers`, `primary_weight` and
    `emission`), sharing its timer, counters, events and their tally; None with direct=pt or
    max_depth < 2."""
    s = integ.settings
    if s.direct != "restir-di" or s.max_depth < 2:
        return None
    di = ReSTIRDI(integ.dscene, di_settings(s), str(integ.device), integ.slices,
                  primary=(integ.gbuffers, integ.primary_weight, integ.emission))
    di.stage_prefix = "di."
    di.timer = integ.timer
    di.counters = integ.counters
    di.events = integ.events
    di.tally = integ.tally  # its events are read with the method's, once per frame
    di.stage_rays = integ.stage_rays  # its rays count in the method's (stats "rays", "rays_by_stage")
    del di.buffers.bytes["events"]
    integ.buffers.bytes.update({f"di.{k}": v for k, v in di.buffers.bytes.items()})
    return di
