"""Hand-off to the tev image viewer (https://github.com/Tom94/tev) through the `tevclient`
package (the optional `tev` extra): `restir render --tev` and `restir compare --tev` send their
images, with AOVs as extra channels, to a running tev over its TCP protocol."""
from .config import ConfigError

DEFAULT_ADDRESS = "127.0.0.1:14158"


def connect_tev(address: str = DEFAULT_ADDRESS):
    """A connected tevclient.Ipc; refuses now (before any render) when tevclient is missing or no
    tev listens at HOST:PORT."""
    try:
        import tevclient
    except ImportError:
        raise ConfigError("--tev needs the tevclient package: pip install 'restir[tev]'") from None
    host, _, port = address.rpartition(":")
    if not host or not port.isdigit():
        raise ConfigError(f"--tev {address}: expected HOST:PORT (tev's default is {DEFAULT_ADDRESS})")
    ipc = tevclient.Ipc(host, int(port))
    try:
        ipc.__enter__()
    except OSError as e:
        raise ConfigError(f"--tev {address}: no tev listening there ({e.strerror or e}); start tev first") from None
    return ipc


def send_to_tev(ipc, name: str, image, layers: dict | None = None) -> None:
    """Create image `name` in tev with channels R, G, B (and name.R/G/B or name.X/Y/Z per layer)."""
    import numpy as np

    channels = {"R": image[..., 0], "G": image[..., 1], "B": image[..., 2]}
    for layer, data in (layers or {}).items():
        for c, s in enumerate(("X", "Y", "Z") if layer == "normal" else ("R", "G", "B")):
            channels[f"{layer}.{s}"] = data[..., c]
    names = list(channels)
    h, w = image.shape[:2]
    ipc.create_image(name, w, h, names)
    ipc.update_image(name, np.ascontiguousarray(np.stack([channels[n] for n in names], -1), np.float32), names)
