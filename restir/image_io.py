"""EXR / PNG / NumPy input and output (and Radiance HDR / PFM input) (linear float RGB arrays of shape (H, W, 3)).

Output formats follow the file's extension (`IMAGE_FORMATS`); `write_image` refuses others.
"""
import os
import tempfile

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
    # OpenEXR does not report a failed write (a full disk): the file is made in a folder of its own,
    # checked, and copied to `path` with Python's I/O, which raises OSError on any failure.
    with tempfile.TemporaryDirectory() as folder:
        tmp = os.path.join(folder, "image.exr")
        with OpenEXR.File(header, channels) as f:
            f.write(tmp)
        try:
            with OpenEXR.File(tmp) as check:
                check.channels()
        except Exception as e:  # noqa: BLE001  (whatever OpenEXR raises for a truncated file)
            raise OSError(f"the EXR could not be written ({e})") from None
        with open(tmp, "rb") as f:
            data = f.read()
    with open(path, "wb") as out:
        out.write(data)


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


def read_pfm(path: str) -> np.ndarray:
    """Portable float map: 'PF' (RGB) or 'Pf' (grey), width height, then a scale whose sign is the
    byte order (negative: little-endian); rows are stored bottom to top."""
    with open(path, "rb") as f:
        data = f.read()
    fields, pos = [], 0
    while len(fields) < 4:  # magic, width, height, scale: whitespace-separated, one byte after the last
        while pos < len(data) and data[pos:pos + 1].isspace():
            pos += 1
        start = pos
        while pos < len(data) and not data[pos:pos + 1].isspace():
            pos += 1
        if start == pos:
            raise ValueError("truncated PFM header")
        fields.append(data[start:pos].decode("ascii", "replace"))
    pos += 1
    if fields[0] not in ("PF", "Pf"):
        raise ValueError(f"not a PFM file (magic '{fields[0]}')")
    w, h, scale = int(fields[1]), int(fields[2]), float(fields[3])
    c = 3 if fields[0] == "PF" else 1
    pixels = np.frombuffer(data, "<f4" if scale < 0 else ">f4", count=w * h * c, offset=pos)
    img = pixels.reshape(h, w, c)[::-1].astype(np.float32)
    return np.repeat(img, 3, axis=2) if c == 1 else img


def _rgbe_scanline(data: bytes, pos: int, w: int) -> tuple[np.ndarray, int]:
    """One scanline of RGBE pixels (w x 4 bytes) at data[pos:], flat or run-length encoded."""
    rle = 8 <= w < 0x8000 and data[pos] == 2 and data[pos + 1] == 2 and not data[pos + 2] & 0x80
    if not rle:  # flat (the old-style run format is not written by current tools: refused)
        line = np.frombuffer(data, np.uint8, count=4 * w, offset=pos).reshape(w, 4)
        if np.any(np.all(line[:, :3] == 1, axis=1)):
            raise ValueError("old-style run-length encoded HDR is not supported")
        return line, pos + 4 * w
    if (data[pos + 2] << 8 | data[pos + 3]) != w:
        raise ValueError("HDR scanline width mismatch")
    pos += 4
    line = np.empty((4, w), np.uint8)
    for c in range(4):  # each channel's bytes as runs (count > 128: one value repeated) or literals
        x = 0
        while x < w:
            count = data[pos]
            if count > 128:
                count -= 128
                line[c, x:x + count] = data[pos + 1]
                pos += 2
            else:
                if count == 0:
                    raise ValueError("corrupt HDR run")
                line[c, x:x + count] = np.frombuffer(data, np.uint8, count=count, offset=pos + 1)
                pos += 1 + count
            x += count
        if x != w:
            raise ValueError("corrupt HDR run")
    return line.T, pos


def read_hdr(path: str) -> np.ndarray:
    """Radiance RGBE (.hdr): the header, a '-Y H +X W' resolution line (rows top to bottom), then
    flat or run-length encoded scanlines; value = mantissa / 256 * 2^(exponent - 128)."""
    with open(path, "rb") as f:
        data = f.read()
    if not (data.startswith(b"#?RADIANCE") or data.startswith(b"#?RGBE")):
        raise ValueError("not a Radiance HDR file")
    end = data.find(b"\n\n")
    if end < 0:
        raise ValueError("truncated HDR header")
    for line in data[:end].split(b"\n"):
        if line.startswith(b"FORMAT=") and line.strip() != b"FORMAT=32-bit_rle_rgbe":
            raise ValueError(f"unsupported HDR {line.decode('ascii', 'replace')} (only 32-bit_rle_rgbe)")
    nl = data.find(b"\n", end + 2)
    res = data[end + 2:nl].split()
    if len(res) != 4 or res[0] != b"-Y" or res[2] != b"+X":
        raise ValueError(f"unsupported HDR orientation '{data[end + 2:nl].decode('ascii', 'replace')}' (only -Y H +X W)")
    h, w = int(res[1]), int(res[3])
    pos = nl + 1
    rgbe = np.empty((h, w, 4), np.uint8)
    for y in range(h):
        rgbe[y], pos = _rgbe_scanline(data, pos, w)
    e = rgbe[..., 3].astype(np.int32)
    scale = np.where(e > 0, np.ldexp(1.0, e - 136), 0.0)  # 2^(e - 128) / 256
    return (rgbe[..., :3] * scale[..., None]).astype(np.float32)


class ImageError(ValueError):
    """A file that cannot be read as an RGB image; the message says why (no library's exception
    type reaches the caller)."""


def read_image(path: str, linearize_srgb: bool = True) -> np.ndarray:
    """Any EXR, Radiance .hdr, .pfm, a .npy array (linear, H x W x 3), or an 8-bit image
    (sRGB-decoded unless linearize_srgb is False), as float32 RGB (H, W, 3) with at least one
    pixel. Anything else raises ImageError."""
    try:
        img = np.asarray(_read_any(path, linearize_srgb))
    except Exception as e:  # the image libraries raise many types for unreadable files
        raise ImageError(f"not a readable image ({type(e).__name__}: {e})") from None
    if img.dtype.kind not in "fiu":
        raise ImageError(f"holds {img.dtype} values, not numbers")
    if img.ndim != 3 or img.shape[2] < 3:
        raise ImageError(f"has the shape {img.shape}, not height x width x 3 (RGB)")
    if img.shape[0] == 0 or img.shape[1] == 0:
        raise ImageError(f"has no pixels ({img.shape[1]}x{img.shape[0]})")
    return np.asarray(img[..., :3], np.float32)


def _read_any(path: str, linearize_srgb: bool) -> np.ndarray:
    lower = path.lower()
    if lower.endswith(".exr"):
        return read_exr(path)
    if lower.endswith(".hdr"):
        return read_hdr(path)
    if lower.endswith(".pfm"):
        return read_pfm(path)
    if lower.endswith(".npy"):
        return np.asarray(np.load(path), np.float32)
    from PIL import Image

    img = np.asarray(Image.open(path).convert("RGB"))
    # by a table of the 256 values (the same float32 arithmetic as on the whole image, 5x faster)
    table = np.arange(256, dtype=np.float32) / np.float32(255.0)
    return (srgb_to_linear(table) if linearize_srgb else table)[img]


def tonemap(rgb: np.ndarray, exposure: float = 0.0) -> np.ndarray:
    """Linear RGB as 8-bit sRGB with exposure (stops); non-finite pixels become black."""
    x = np.nan_to_num(np.asarray(rgb, np.float64) * (2.0 ** exposure), nan=0.0, posinf=0.0, neginf=0.0)
    return (linear_to_srgb(x) * 255.0 + 0.5).astype(np.uint8)


def write_png(path: str, rgb: np.ndarray, exposure: float = 0.0) -> None:
    """Tonemap linear RGB with exposure (stops) and the sRGB curve; non-finite pixels become black."""
    from PIL import Image

    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    Image.fromarray(tonemap(rgb, exposure)).save(path)


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
