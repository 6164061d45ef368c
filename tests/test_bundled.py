import sys
import zipfile
from pathlib import Path

import pytest

from cable_ocp import load_scene
from cable_ocp.scene import bundled

if sys.version_info >= (3, 11):
    import tomllib
else:
    import tomli as tomllib

ROOT = Path(__file__).resolve().parent.parent
SCENES = {
    "catenary", "deploy", "end_force", "hanging", "paper_flat", "paper_hill", "small_tow", "survey",
}  # fmt: skip


def test_models_dir_holds_the_eight_scenes_and_each_loads():
    folder = bundled.models_dir()
    assert folder.is_dir()
    assert SCENES <= set(bundled.scene_names())
    for name in SCENES:
        assert load_scene(folder / f"{name}.toml").name == name


def test_scene_path_by_name_with_or_without_suffix():
    assert bundled.scene_path("paper_hill") == bundled.models_dir() / "paper_hill.toml"
    assert bundled.scene_path("paper_hill.toml") == bundled.scene_path("paper_hill")


def test_unknown_scene_name_lists_the_bundled_ones():
    with pytest.raises(ValueError, match="'nope' is not a bundled scene") as info:
        bundled.scene_path("nope")
    for name in SCENES:
        assert name in str(info.value)


def test_scenes_inside_a_zip_fail_clearly(monkeypatch, tmp_path):
    archive = tmp_path / "cable_ocp.zip"
    with zipfile.ZipFile(archive, "w") as z:
        z.writestr("cable_ocp/models/hanging.toml", "")
    monkeypatch.setattr(
        bundled.resources, "files", lambda _: zipfile.Path(archive, "cable_ocp/models/")
    )
    with pytest.raises(RuntimeError, match="not on the file system"):
        bundled.models_dir()


def test_pyproject_lists_every_subpackage_and_ships_the_data():
    setuptools = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    inits = (ROOT / "cable_ocp").rglob("__init__.py")
    found = {".".join(init.parent.relative_to(ROOT).parts) for init in inits}
    assert found | {"cable_ocp.models"} == set(setuptools["packages"])
    assert setuptools["package-dir"] == {"cable_ocp.models": "models"}
    assert setuptools["package-data"]["cable_ocp.models"] == [
        "*.toml",
        "sweeps/*.toml",
        "families/*.toml",
        "data/*.nc",
    ]
    for pattern in setuptools["package-data"]["cable_ocp"]:
        assert list((ROOT / "cable_ocp").glob(pattern)), pattern
