"""The settings of a spatial-reuse pass, declared once for every method that has one (ReSTIR DI,
ReSTIR PT, Suffix ReSTIR's suffix reuse): rounds, neighbours per round and the disk radius,
nested under the method's prefix (`spatial.*`, `suffix.spatial.*`) with the method's defaults.
"""
import dataclasses

from ...settings import SettingsGroup, component, setting
from ...device.streams import MAX_SPATIAL_ROUNDS
from .reuse_domains import resolve_spatial_radius


@dataclasses.dataclass
class SpatialReuseSettings(SettingsGroup):
    rounds: int = setting("rounds", 1, "spatial reuse rounds (pairwise MIS)")
    neighbors: int = setting("neighbors", 3, "neighbours per round")
    radius: str = setting("radius", "auto", "neighbour disk radius in pixels; auto: {radius_at_1080:g} px up to "
                          "1080 lines, scaled with the height above")
    reciprocal: bool = setting("reciprocal", False, "neighbours in pairs, each pixel the neighbour of its "
                               "neighbour, so that one pair of shifts serves both: k shifts per pixel instead of 2k "
                               "(ReSTIR PT Enhanced's reciprocal selection; the same estimator, other neighbours)",
                               static=True)
    # not settings: what the method fixes (its keys' prefix, for messages; its "auto" radius)
    prefix: str = "spatial."
    radius_at_1080: float = 20.0

    def check(self, max_neighbors: int) -> None:
        """ConfigError unless rounds, neighbours and radius are in range."""
        from ...config import ConfigError

        if not 0 <= self.rounds <= MAX_SPATIAL_ROUNDS or not 1 <= self.neighbors <= max_neighbors:
            raise ConfigError(f"{self.prefix}rounds must be in [0, {MAX_SPATIAL_ROUNDS}] and {self.prefix}neighbors "
                              f"in [1, {max_neighbors}]")
        resolve_spatial_radius(self.radius, self.radius_at_1080, 1)  # raises if invalid

    def resolve_radius(self, height: int) -> float:
        """The radius in pixels for an image `height` lines high; "auto" is replaced by it, so the
        stats report the pixels used."""
        pixels = resolve_spatial_radius(self.radius, self.radius_at_1080, height)
        if self.radius == "auto":
            self.radius = pixels
        return pixels


def spatial_reuse(prefix: str, radius_at_1080: float, rounds: int = 1, doc_prefix: str = "",
                  reciprocal: bool | None = None):
    """A method's spatial-reuse settings field: keys under `prefix` ("spatial."), `rounds` by
    default, "auto" meaning `radius_at_1080` pixels at 1080 lines. reciprocal: the default of
    `reciprocal` for a method whose pass has the reciprocal form; None: the method has no such
    key (ReSTIR DI's and Suffix ReSTIR's passes)."""
    return component(prefix, lambda: SpatialReuseSettings(rounds=rounds, prefix=prefix, radius_at_1080=radius_at_1080,
                                                          reciprocal=bool(reciprocal)),
                     doc_prefix, exclude=("reciprocal",) if reciprocal is None else (),
                     doc_args={"radius_at_1080": radius_at_1080})
