"""AOVs as EXR layers (`render --aov`), the hand-off to tev (`--tev`, against a stand-in tev
server speaking its TCP protocol), and the denoised view of `compare --denoise`."""
import socket
import struct
import threading

import numpy as np
import pytest

import restir
from restir.cli import main
from restir.image_io import read_exr_layers
from restir.scene.builtin import GREEN, RED, WHITE


def test_aovs_are_exr_layers(tmp_path):
    out = tmp_path / "cb.exr"
    assert main(["render", "builtin:cornell-box", "--width", "32", "--height", "32", "--spp", "2", "--frames", "4",
                 "--aov", "albedo,normal", "-o", str(out), "--quiet"]) == 0
    layers = read_exr_layers(str(out))
    assert set(layers) == {"", "albedo", "normal"}
    rgb = restir.render(restir.load_scene("builtin:cornell-box"), spp=2, frames=4, width=32, height=32).image
    assert np.array_equal(layers[""], rgb)  # the radiance is the render's, bitwise
    albedo, normal = layers["albedo"], layers["normal"]
    # the left wall is red, the right green, the back white: a pixel well inside each
    for (y, x), want in (((16, 1), RED), ((16, 30), GREEN), ((10, 16), WHITE)):
        assert np.allclose(albedo[y, x], want, atol=1e-5), ((y, x), albedo[y, x], want)
    assert np.allclose(np.linalg.norm(normal[10, 16]), 1.0, atol=1e-5)
    assert normal[10, 16] @ normal[16, 1] == pytest.approx(0.0, abs=1e-4)  # back wall vs left wall


def test_aov_errors(tmp_path, capsys):
    for args, msg in ((["--aov", "albedo", "-o", str(tmp_path / "x.png")], "not .exr"),
                      (["--aov", "albedo,depth", "-o", str(tmp_path / "x.exr")], "unknown AOV depth")):
        assert main(["render", "builtin:cornell-box", "--width", "8", "--height", "8", *args]) == 2
        assert msg in capsys.readouterr().err
    assert not list(tmp_path.iterdir())


class FakeTev(threading.Thread):
    """Accepts one connection on a free port and parses tev's packets (little-endian uint32 size
    including itself, one type byte, payload) until the client closes."""

    def __init__(self):
        super().__init__(daemon=True)
        self.server = socket.socket()
        self.server.bind(("127.0.0.1", 0))
        self.server.listen(1)
        self.port = self.server.getsockname()[1]
        self.packets = []

    def run(self):
        conn, _ = self.server.accept()
        data = b""
        while chunk := conn.recv(1 << 16):
            data += chunk
        conn.close()
        while len(data) >= 5:
            size = struct.unpack("<I", data[:4])[0]
            self.packets.append((data[4], data[5:size]))
            data = data[size:]


def test_render_sends_to_tev(tmp_path):
    tev = FakeTev()
    tev.start()
    assert main(["render", "builtin:cornell-box", "--width", "16", "--height", "12", "--spp", "1", "--aov",
                 "albedo,normal", "-o", str(tmp_path / "x.exr"), "--tev", f"127.0.0.1:{tev.port}", "--quiet"]) == 0
    tev.join(timeout=30)
    kinds = [k for k, _ in tev.packets]
    assert kinds and kinds[0] == 4  # CreateImage, then UpdateImage packets with the pixels
    create = tev.packets[0][1]
    for name in (b"R", b"G", b"B", b"albedo.R", b"normal.Z"):
        assert name + b"\0" in create
    pixels = sum(len(p) for k, p in tev.packets[1:])
    assert pixels >= 16 * 12 * 9 * 4  # nine float32 channels


def test_tev_refused_before_work(tmp_path, capsys):
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()  # nothing listens there now
    assert main(["render", "builtin:cornell-box", "--width", "8", "--height", "8", "-o", str(tmp_path / "x.exr"),
                 "--tev", f"127.0.0.1:{port}"]) == 2
    assert "no tev listening" in capsys.readouterr().err and not (tmp_path / "x.exr").exists()


def test_compare_denoises_the_measured_frames(tmp_path, monkeypatch):
    """On a smooth scene (the Cornell box's diffuse walls) OIDN removes most of a 4-spp frame's
    error: the denoised per-frame relMSE, over the same frames, is well below the raw one, and
    so is FLIP."""
    from restir.compare import compare
    from restir.compare.report import write_report

    monkeypatch.setenv("RESTIR_CACHE", str(tmp_path))
    r = compare(restir.load_scene("builtin:cornell-box"), ["pt:spp=4"], reference_spp=256, frames=6, warmup=2,
                width=48, height=48, max_depth=4, denoise=True, correlation_runs=0)
    m = r.methods[0]
    assert m.denoised.shape == (48, 48, 3) and np.all(np.isfinite(m.denoised))
    assert m.denoise_subset == [2, 3, 4, 5] and m.metrics["denoised_frames"] == 4
    assert m.metrics["relmse_frame_subset"] == pytest.approx(np.mean(m.frame_relmse[2:]), rel=1e-4)
    # OIDN on a 4-spp frame: several times lower error than the frames themselves
    assert m.metrics["relmse_denoised_frame"] < 0.5 * m.metrics["relmse_frame_subset"], m.metrics
    assert m.metrics["flip_denoised_frame"] < m.metrics["flip_frame"], m.metrics
    assert "denoised by Open Image Denoise on the host CPU" in r.notes
    index = write_report(r, str(tmp_path / "rep"))
    assert "last frame denoised" in open(index).read() + open(tmp_path / "rep" / "data.js").read()


def test_a_gpu_denoiser_that_fails_falls_back_to_the_host():
    """Where the GPU path cannot run (no PyTorch with CUDA here), the denoiser says why and gives
    the host's image, for that frame and every later one."""
    from restir.compare.denoise import Denoiser

    rng = np.random.default_rng(1)
    albedo = rng.uniform(0.2, 0.8, (16, 16, 3)).astype(np.float32)
    normal = np.broadcast_to(np.array([0, 0, 1], np.float32), (16, 16, 3)).copy()
    frame = rng.exponential(0.5, (16, 16, 3)).astype(np.float32)
    host = Denoiser(albedo, normal)(frame)
    gpu = Denoiser(albedo, normal, device="cuda")
    assert np.allclose(gpu(frame), host, rtol=1e-5, atol=1e-6)
    assert gpu.device == "cpu" and gpu.fallback and gpu.where.startswith("the host CPU; the GPU was tried and failed")
    assert np.allclose(gpu(frame), host, rtol=1e-5, atol=1e-6)

