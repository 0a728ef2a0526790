"""Where the tests find the shared scenes (cornell-box/, veach-mis/, veach-bidir/, each with a
scene.xml): the folder named by $RESTIR_SCENES, else ../shared/scenes beside the checkout.
Tests that need them skip, naming the variable, when neither is there."""
import os
import pathlib

import pytest

SCENES_ENV = "RESTIR_SCENES"
DEFAULT = pathlib.Path(__file__).resolve().parents[2] / "shared" / "scenes"


def _candidate() -> pathlib.Path:
    value = os.environ.get(SCENES_ENV, "").strip()
    return pathlib.Path(value).expanduser() if value else DEFAULT


def scenes_dir() -> pathlib.Path | None:
    """The shared scenes folder, or None when it is missing."""
    path = _candidate()
    return path if path.is_dir() else None


def skip_reason() -> str:
    where = f"{SCENES_ENV}={_candidate()}" if os.environ.get(SCENES_ENV, "").strip() else f"{DEFAULT} (the default)"
    return f"shared scenes not found at {where}: set {SCENES_ENV} to the folder holding cornell-box/, veach-mis/, ..."


def scene_path(name: str) -> pathlib.Path:
    """<scenes>/<name>/scene.xml; skips the calling test when it is not there."""
    root = scenes_dir()
    if root is None:
        pytest.skip(skip_reason())
    path = root / name / "scene.xml"
    if not path.is_file():
        pytest.skip(f"{path} not found ({SCENES_ENV} names the shared scenes folder)")
    return path


# For @pytest.mark.skipif at collection time.
requires_scenes = pytest.mark.skipif(scenes_dir() is None, reason=skip_reason())


PBRT_ENV = "RESTIR_PBRT_SCENES"
PBRT_DEFAULT = pathlib.Path(__file__).resolve().parents[2] / "pbrt-scenes"


def pbrt_scene_path(rel: str) -> pathlib.Path:
    """A file of the pbrt-v4 scenes (a checkout of w3ntao/pbrt-minus-scenes) in the folder named by
    $RESTIR_PBRT_SCENES, else ../pbrt-scenes beside the checkout; skips the calling test when it is
    not there."""
    value = os.environ.get(PBRT_ENV, "").strip()
    root = pathlib.Path(value).expanduser() if value else PBRT_DEFAULT
    path = root / rel
    if not path.is_file():
        pytest.skip(f"{path} not found: set {PBRT_ENV} to a checkout of w3ntao/pbrt-minus-scenes")
    return path
