"""Radiance HDR and PFM input (environment maps and bitmaps as distributed): files written here
byte by byte from the formats' definitions, read back exactly; and, with Mitsuba 3 installed (the
`reference` extra, slow tier), read as Mitsuba's own Bitmap reads them."""
import numpy as np
import pytest

from restir.image_io import read_hdr, read_image, read_pfm

RNG = np.random.default_rng(7)
# RGBE-representable values: mantissas 128-255 of a shared exponent per pixel, a few zero pixels
H, W = 5, 19
RGBE = np.concatenate([RNG.integers(0, 256, (H, W, 3)), RNG.integers(120, 140, (H, W, 1))], -1).astype(np.uint8)
RGBE[1, 3:12] = RGBE[1, 3]   # a run, so the encoder writes run packets too
RGBE[2, 5] = 0               # black: exponent 0
EXPECTED = RGBE[..., :3] * np.where(RGBE[..., 3:] > 0, 2.0 ** (RGBE[..., 3:].astype(float) - 136), 0.0)


def _rle_channel(values: np.ndarray) -> bytes:
    out, x = bytearray(), 0
    while x < len(values):
        run = 1
        while x + run < len(values) and run < 127 and values[x + run] == values[x]:
            run += 1
        if run >= 3:
            out += bytes([128 + run, values[x]])
            x += run
        else:
            n = 1
            while x + n < len(values) and n < 128 and not (x + n + 2 < len(values) and
                                                           values[x + n] == values[x + n + 1] == values[x + n + 2]):
                n += 1
            out += bytes([n]) + bytes(values[x:x + n])
            x += n
    return bytes(out)


def write_hdr(path, rgbe: np.ndarray, rle: bool) -> None:
    h, w = rgbe.shape[:2]
    data = bytearray(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\nEXPOSURE=1.0\n\n" + f"-Y {h} +X {w}\n".encode())
    for y in range(h):
        if rle:
            data += bytes([2, 2, w >> 8, w & 255])
            for c in range(4):
                data += _rle_channel(rgbe[y, :, c])
        else:
            data += rgbe[y].tobytes()
    path.write_bytes(bytes(data))


def write_pfm(path, img: np.ndarray, little: bool, grey: bool = False) -> None:
    h, w = img.shape[:2]
    body = (img[..., :1] if grey else img)[::-1].astype("<f4" if little else ">f4").tobytes()
    path.write_bytes(f"{'Pf' if grey else 'PF'}\n{w} {h}\n{-1.0 if little else 1.0}\n".encode() + body)


@pytest.mark.parametrize("rle", [True, False], ids=["rle", "flat"])
def test_hdr_reads_exactly(tmp_path, rle):
    write_hdr(tmp_path / "a.hdr", RGBE, rle)
    np.testing.assert_array_equal(read_hdr(str(tmp_path / "a.hdr")), EXPECTED.astype(np.float32))
    np.testing.assert_array_equal(read_image(str(tmp_path / "a.hdr")), EXPECTED.astype(np.float32))


@pytest.mark.parametrize("little", [True, False], ids=["little-endian", "big-endian"])
def test_pfm_reads_exactly(tmp_path, little):
    img = RNG.normal(size=(4, 7, 3)).astype(np.float32) * 100
    write_pfm(tmp_path / "a.pfm", img, little)
    np.testing.assert_array_equal(read_pfm(str(tmp_path / "a.pfm")), img)
    write_pfm(tmp_path / "g.pfm", img, little, grey=True)
    np.testing.assert_array_equal(read_image(str(tmp_path / "g.pfm")), np.repeat(img[..., :1], 3, 2))


def test_bad_files_refused(tmp_path):
    (tmp_path / "x.hdr").write_bytes(b"P6\n1 1\n255\n\x00\x00\x00")
    with pytest.raises(ValueError, match="not a Radiance"):
        read_hdr(str(tmp_path / "x.hdr"))
    (tmp_path / "y.hdr").write_bytes(b"#?RADIANCE\nFORMAT=32-bit_rle_xyze\n\n+Y 1 +X 1\n\x00\x00\x00\x00")
    with pytest.raises(ValueError, match="xyze"):
        read_hdr(str(tmp_path / "y.hdr"))
    (tmp_path / "z.pfm").write_bytes(b"P7\n1 1\n-1\n" + bytes(12))
    with pytest.raises(ValueError, match="not a PFM"):
        read_pfm(str(tmp_path / "z.pfm"))


@pytest.mark.slow
def test_as_mitsuba_reads_them(tmp_path):
    mi = pytest.importorskip("mitsuba")
    mi.set_variant("scalar_rgb")
    write_hdr(tmp_path / "a.hdr", RGBE, rle=True)
    img = RNG.uniform(0, 50, size=(4, 7, 3)).astype(np.float32)
    write_pfm(tmp_path / "a.pfm", img, little=True)
    for name in ("a.hdr", "a.pfm"):
        ours = read_image(str(tmp_path / name))
        theirs = np.asarray(mi.Bitmap(str(tmp_path / name)), np.float32)[..., :3]
        np.testing.assert_allclose(ours, theirs, rtol=1e-6, err_msg=name)
