"""A scene file as the loaders read it: refused from its stat, before it is opened, when it is not
a regular file (a folder, a device such as /dev/zero, a FIFO that would block) or larger than
limits.MAX_SCENE_FILE_BYTES (its meshes and images belong in files of their own)."""
import os
import stat

from .. import limits
from .errors import SceneError


def check_scene_file(path: str) -> None:
    try:
        st = os.stat(path)
    except OSError as e:
        raise SceneError(f"cannot read scene file: {e.strerror}", path) from None
    if not stat.S_ISREG(st.st_mode):
        raise SceneError("the scene is not a regular file (a folder, device or pipe)", path)
    if st.st_size > limits.MAX_SCENE_FILE_BYTES:
        raise SceneError(f"the scene file is {st.st_size >> 20} MiB: at most {limits.MAX_SCENE_FILE_BYTES >> 20} MiB "
                         "(meshes and images belong in files of their own)", path)


def read_scene_file(path: str) -> bytes:
    check_scene_file(path)
    try:
        with open(path, "rb") as f:
            return f.read(limits.MAX_SCENE_FILE_BYTES + 1)
    except OSError as e:
        raise SceneError(f"cannot read scene file: {e.strerror}", path) from None
