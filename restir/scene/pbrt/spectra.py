"""pbrt-v4's spectra as the RGB restir renders (docs/guide/pbrt.md#spectra).

pbrt-v4 renders spectrally; restir renders linear sRGB. A parameter becomes RGB by its role:
- an emitter's spectrum (`L`, `I`): pbrt-v4 divides it by its luminance (the area light's
  `scale` then sets the luminance), so restir takes its colour at luminance 1: an `rgb` value as
  written (pbrt-v4's RGB illuminant spectrum has that colour at that luminance), a `blackbody`
  temperature by Planck's law through the CIE 1931 functions (Wyman, Sloan and Shirley's
  piecewise-Gaussian fit, within 0.5% of the tables), a named illuminant from named_spectra.py,
  and wavelength-value pairs through the same fit;
- a reflectance or a conductor's eta and k: `rgb` as written, a named metal from named_spectra.py;
- a dielectric's eta: one number (a named glass's luminance-weighted IOR; pairs: the same
  average); pbrt-v4 renders the dispersion, restir does not (said with a warning).
"""
import numpy as np

from ..errors import SceneError, warn
from .named_spectra import CONDUCTORS, GLASSES, ILLUMINANTS

XYZ_TO_SRGB = np.array([[3.2404542, -1.5371385, -0.4985314],
                        [-0.9692660, 1.8760108, 0.0415560],
                        [0.0556434, -0.2040259, 1.0572252]])
LAMBDA = np.arange(360.0, 831.0, 1.0)   # nm: the CIE functions' range, as pbrt-v4 integrates


def _lobe(lam, mu, s1, s2):
    s = np.where(lam < mu, s1, s2)
    return np.exp(-0.5 * ((lam - mu) / s) ** 2)


def cie_xyz(lam: np.ndarray) -> np.ndarray:
    """The CIE 1931 2-degree colour-matching functions by the multi-lobe fit of Wyman, Sloan and
    Shirley (JCGT 2013), (3, N)."""
    x = 1.056 * _lobe(lam, 599.8, 37.9, 31.0) + 0.362 * _lobe(lam, 442.0, 16.0, 26.7) - 0.065 * _lobe(lam, 501.1, 20.4, 26.2)
    y = 0.821 * _lobe(lam, 568.8, 46.9, 40.5) + 0.286 * _lobe(lam, 530.9, 16.3, 31.1)
    z = 1.217 * _lobe(lam, 437.0, 11.8, 36.0) + 0.681 * _lobe(lam, 459.0, 26.0, 13.8)
    return np.stack([x, y, z])


def emitter_rgb_of_samples(values: np.ndarray) -> np.ndarray:
    """Linear sRGB at luminance 1 of an emission spectrum sampled at LAMBDA."""
    xyz = cie_xyz(LAMBDA) @ values
    if xyz[1] <= 0:
        raise ValueError("the spectrum has no luminance")
    return XYZ_TO_SRGB @ (xyz / xyz[1])


def blackbody_rgb(kelvin: float) -> np.ndarray:
    """A blackbody's colour at luminance 1 (Planck's law; the constant factors cancel)."""
    b = 1.0 / LAMBDA ** 5 / np.expm1(1.4387769e7 / (LAMBDA * kelvin))  # hc/k in nm K
    return emitter_rgb_of_samples(b)


def _pairs(pairs: np.ndarray, loc: str) -> np.ndarray:
    lam, val = pairs[:, 0], pairs[:, 1]
    if np.any(np.diff(lam) <= 0):
        raise SceneError("a spectrum's wavelengths must increase", loc)
    return np.interp(LAMBDA, lam, val, left=0.0, right=0.0)  # pbrt-v4: zero outside the samples


def emission(spec, loc: str) -> np.ndarray:
    """An emitter's spectrum (ParamSet.spectrum's tuple) as RGB at luminance 1 (rgb: as written)."""
    kind, v = spec
    if kind == "rgb":
        if np.any(v < 0):
            raise SceneError("an emitter's rgb must be non-negative", loc)
        return v
    if kind == "blackbody":
        if v <= 0:
            raise SceneError("a blackbody temperature must be positive (kelvin)", loc)
        rgb = blackbody_rgb(v)
    elif kind == "named":
        if v not in ILLUMINANTS:
            raise SceneError(f"unknown illuminant spectrum '{v}' (known: {', '.join(ILLUMINANTS)})", loc)
        rgb = np.array(ILLUMINANTS[v])
    else:
        if np.any(v[:, 1] < 0):
            raise SceneError("an emission spectrum must be non-negative", loc)
        try:
            rgb = emitter_rgb_of_samples(_pairs(v, loc))
        except ValueError:
            raise SceneError("the emission spectrum has no luminance (all of it outside 360-830 nm?)", loc) from None
    if np.any(rgb < 0):
        warn(f"the spectrum's colour is outside sRGB: its negative components ({_fmt(rgb)}) are set to 0", loc)
        rgb = np.maximum(rgb, 0.0)
    return rgb


def conductor(eta_spec, k_spec, loc_eta: str, loc_k: str) -> tuple[np.ndarray, np.ndarray]:
    """A conductor's (eta, k) RGB; named metals must come as a matching pair."""
    out = []
    for spec, part, loc in ((eta_spec, "eta", loc_eta), (k_spec, "k", loc_k)):
        kind, v = spec
        if kind == "rgb":
            out.append(v)
        elif kind == "named":
            metal = _metal(v, part, loc)
            out.append(np.array(CONDUCTORS[metal][0 if part == "eta" else 1]))
        else:
            raise SceneError(f"a conductor's {part} must be rgb or a named metal spectrum (metal-*-{part}); "
                             f"{'blackbody' if kind == 'blackbody' else 'wavelength-value pairs'} is not supported", loc)
    if eta_spec[0] == "named" and k_spec[0] == "named" and _metal(eta_spec[1], "eta", loc_eta) != _metal(k_spec[1], "k", loc_k):
        warn("the conductor's eta and k name different metals", loc_eta)
    return out[0], out[1]


def _metal(name: str, part: str, loc: str) -> str:
    if not (name.startswith("metal-") and name.endswith(f"-{part}") and name[6:-len(part) - 1] in CONDUCTORS):
        raise SceneError(f"unknown conductor spectrum '{name}' for {part} (known: "
                         f"{', '.join(f'metal-{m}-{part}' for m in CONDUCTORS)})", loc)
    return name[6:-len(part) - 1]


def dielectric_eta(spec, loc: str) -> float:
    """A dielectric's IOR from a named glass or wavelength-value pairs, with a warning that the
    dispersion pbrt-v4 renders is not."""
    kind, v = spec
    if kind == "named":
        if not v.startswith("glass-") or v[6:] not in GLASSES:
            raise SceneError(f"unknown glass spectrum '{v}' (known: {', '.join('glass-' + g for g in GLASSES)})", loc)
        eta = GLASSES[v[6:]]
    elif kind == "spectrum":
        samples = np.interp(LAMBDA, v[:, 0], v[:, 1])  # held constant outside, as an IOR should be
        y = cie_xyz(LAMBDA)[1]
        eta = float(y @ samples / y.sum())
    else:
        raise SceneError("a dielectric's eta is a number, a named glass or wavelength-value pairs", loc)
    warn(f"the dielectric's eta varies with wavelength: rendered with one IOR, {eta:.4f} (luminance-weighted); "
         "pbrt-v4 renders the dispersion", loc)
    return eta


def reflectance(spec, loc: str) -> np.ndarray:
    kind, v = spec
    if kind == "rgb":
        return v
    raise SceneError("a reflectance must be rgb or a texture here (spectral reflectances are not supported)", loc)


def _fmt(v) -> str:
    return " ".join(f"{x:.3g}" for x in v)
