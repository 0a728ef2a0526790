"""Textures as the loader reads them (Mitsuba 3's `bitmap` and `checkerboard`), before upload.

Semantics follow Mitsuba 3: a bitmap's uv (0, 0) is its top-left texel; `filter_type` nearest or
bilinear (default), `wrap_mode` repeat (default), mirror or clamp; `raw` keeps 8-bit images
un-linearized. A checkerboard is color0 where frac(u) and frac(v) are both above 1/2 or both
not, color1 elsewhere (defaults 0.4 and 0.2; Mitsuba 3.9.1's own `eval`, checked point by point). Both apply `to_uv` to the surface's uv first (`uv_transform`). The mean is
what sampling weights use (plastic's specular sampling weight), as Mitsuba's `mean()`.
"""
from dataclasses import dataclass, field

import numpy as np

FILTERS = ("nearest", "bilinear")
WRAPS = ("repeat", "mirror", "clamp")


@dataclass
class TextureDesc:
    kind: str                                   # "bitmap" | "checkerboard"
    to_uv: np.ndarray = field(default_factory=lambda: np.eye(3))
    image: np.ndarray | None = None             # bitmap: (H, W, 3) linear RGB
    filter: str = "bilinear"                    # bitmap: one of FILTERS
    wrap: str = "repeat"                        # bitmap: one of WRAPS
    color0: np.ndarray = field(default_factory=lambda: np.full(3, 0.4))   # checkerboard
    color1: np.ndarray = field(default_factory=lambda: np.full(3, 0.2))

    def mean(self) -> float:
        if self.kind == "checkerboard":
            return 0.5 * (float(np.mean(self.color0)) + float(np.mean(self.color1)))
        return float(self.image.mean())


def uv_transform(m4: np.ndarray) -> tuple[np.ndarray, bool]:
    """`to_uv` as Mitsuba 3.9.1 applies it: the 4x4 transform's x and y rows and its x, y and
    translation columns, an affine map of (u, v, 1) (so `<translate x=.. y=..>` offsets uv; checked
    against Mitsuba point by point). Also whether a z column entry was dropped from those rows: a
    3x3 `<matrix>` puts its uv offset there, and Mitsuba ignores it."""
    keep = [0, 1, 3]
    return m4[np.ix_(keep, keep)].copy(), bool(m4[0, 2] != 0.0 or m4[1, 2] != 0.0)
