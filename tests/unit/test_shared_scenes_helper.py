"""tests/shared_scenes.py: the shared scenes are found through RESTIR_SCENES, or beside the checkout."""
import pytest

from tests import shared_scenes as helper


def test_environment_variable_points_at_the_scenes(tmp_path, monkeypatch):
    (tmp_path / "cornell-box").mkdir()
    (tmp_path / "cornell-box" / "scene.xml").write_text("<scene version='3.0.0'/>")
    monkeypatch.setenv(helper.SCENES_ENV, str(tmp_path))
    assert helper.SCENES_ENV == "RESTIR_SCENES"
    assert helper.scenes_dir() == tmp_path
    assert helper.scene_path("cornell-box") == tmp_path / "cornell-box" / "scene.xml"


def test_missing_scenes_skip_with_a_reason_naming_the_variable(tmp_path, monkeypatch):
    monkeypatch.setenv(helper.SCENES_ENV, str(tmp_path / "nowhere"))
    assert helper.scenes_dir() is None
    assert "RESTIR_SCENES" in helper.skip_reason() and str(tmp_path / "nowhere") in helper.skip_reason()
    with pytest.raises(pytest.skip.Exception, match="RESTIR_SCENES"):
        helper.scene_path("cornell-box")


def test_default_is_beside_the_checkout(monkeypatch):
    import pathlib

    monkeypatch.delenv(helper.SCENES_ENV, raising=False)
    default = pathlib.Path(helper.__file__).resolve().parents[2] / "shared" / "scenes"
    assert helper.scenes_dir() == (default if default.is_dir() else None)
