"""EXR / PNG / NumPy input and output (linear float RGB arrays of shape (H, W, 3)).

Output formats follow the file's extension (`IMAGE_FORMATS`); `write_image` refuses others.
"""
import os

import numpy as np


def write_exr(path: str, rgb: np.ndarray, layers: dict | None = None) -> None:
    """rgb as the R, G, B channels; layers {name: (H, W, 3) array, ...} as further channels
    name.R/G/B, or name.X/Y/Z for normals (restir/aov.py CHANNELS), as Mitsuba's aov integrator."""
    import OpenEXR

    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    channels = {"RGB": np.ascontiguousarray(rgb, dtype=np.float32)}
    for name, image in (layers or {}).items():
        suffixes = ("X", "Y", "Z") if name == "normal" else ("R", "G", "B")
        for c, suffix in enumerate(suffixes):
            channels[f"{name}.{suffix}"] = np.ascontiguousarray(np.asarray(image)[..., c], dtype=np.float32)
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    with OpenEXR.File(header, channels) as f:
        f.write(path)


def read_exr_layers(path: str) -> dict:
    """{layer: (H, W, 3)} of an EXR written with layers (see write_exr); "" is the RGB image."""
    import OpenEXR

    with OpenEXR.File(path, separate_channels=True) as f:
        ch = {k: np.asarray(v.pixels, np.float32) for k, v in f.channels().items()}
    out = {}
    for name in sorted({k.rsplit(".", 1)[0] if "." in k else "" for k in ch}):
        prefix = name + "." if name else ""
        suffixes = ("X", "Y", "Z") if name == "normal" else ("R", "G", "B")
        if all(prefix + s in ch for s in suffixes):
            out[name] = np.stack([ch[prefix + s] for s in suffixes], -1)
    return out


def read_exr(path: str) -> np.ndarray:
    import OpenEXR

    with OpenEXR.File(path) as f:
        ch = f.channels()
        if "RGB" in ch:
            return np.asarray(ch["RGB"].pixels, np.float32)[..., :3]
        if "RGBA" in ch:
            return np.asarray(ch["RGBA"].pixels, np.float32)[..., :3]
        return np.stack([np.asarray(ch[c].pixels, np.float32) for c in "RGB"], -1)


def srgb_to_linear(x: np.ndarray) -> np.ndarray:
    return np.where(x <= 0.04045, x / 12.92, ((x + 0.055) / 1.055) ** 2.4)


def linear_to_srgb(x: np.ndarray) -> np.ndarray:
    x = np.clip(x, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def read_image(path: str, linearize_srgb: bool = True) -> np.ndarray:
    """Any EXR, a .npy array (linear, H x W x 3), or an 8-bit image (sRGB-decoded unless
    linearize_srgb is False), as float RGB."""
    if path.lower().endswith(".exr"):
        return read_exr(path)
    if path.lower().endswith(".npy"):
        return np.asarray(np.load(path), np.float32)
    from PIL import Image

    img = np.asarray(Image.open(path).convert("RGB"), np.float32) / 255.0
    return srgb_to_linear(img) if linearize_srgb else img


def write_png(path: str, rgb: np.ndarray, exposure: float = 0.0) -> None:
    """Tonemap linear RGB with exposure (stops) and the sRGB curve; non-finite pixels become black."""
    from PIL import Image

    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    x = np.nan_to_num(np.asarray(rgb, np.float64) * (2.0 ** exposure), nan=0.0, posinf=0.0, neginf=0.0)
    Image.fromarray((linear_to_srgb(x) * 255.0 + 0.5).astype(np.uint8)).save(path)


# Extension -> what write_image writes there.
IMAGE_FORMATS = {
    ".exr": "OpenEXR, linear float RGB",
    ".png": "PNG, tonemapped sRGB (8 bits, with the exposure)",
    ".jpg": "JPEG, tonemapped sRGB",
    ".jpeg": "JPEG, tonemapped sRGB",
    ".npy": "NumPy array, float32 linear RGB of shape (H, W, 3)",
}
LDR_FORMATS = (".png", ".jpg", ".jpeg")


def image_format(path: str) -> str:
    """The output format's extension ('.exr', ...); ValueError for one write_image cannot write."""
    ext = os.path.splitext(path)[1].lower()
    if ext not in IMAGE_FORMATS:
        raise ValueError(f"unsupported extension '{ext}' (use {', '.join(IMAGE_FORMATS)})" if ext else
                         f"no extension to choose the format by (use {', '.join(IMAGE_FORMATS)})")
    return ext


def write_npy(path: str, rgb: np.ndarray) -> None:
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    np.save(path, np.ascontiguousarray(rgb, dtype=np.float32))


def write_image(path: str, rgb: np.ndarray, exposure: float = 0.0) -> None:
    """Write `rgb` in the format of the path's extension (IMAGE_FORMATS); the exposure applies
    to the tonemapped 8-bit formats only."""
    ext = image_format(path)
    if ext == ".exr":
        write_exr(path, rgb)
    elif ext == ".npy":
        write_npy(path, rgb)
    else:
        write_png(path, rgb, exposure)
