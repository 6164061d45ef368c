"""The front doors take a scene, a scene file's path or a bundled name (issue 45, item 8)."""

from pathlib import Path

import pytest

import cable_ocp as co
from cable_ocp.scene.given import scene_given
from cable_ocp.scene.schema import SceneError


def test_a_name_or_a_path_is_loaded_and_a_scene_passes_through(models_dir):
    by_name = scene_given("small_tow", "optimize")
    assert by_name == co.load_scene(models_dir / "small_tow.toml")
    assert scene_given(models_dir / "small_tow.toml", "optimize") == by_name
    assert scene_given(by_name, "optimize") is by_name


def test_anything_else_is_refused_naming_the_function_and_what_it_takes():
    with pytest.raises(TypeError, match=r"^land: scene must be a Scene .* got dict"):
        scene_given({"model": {}}, "land")


def test_optimize_and_land_read_a_path_or_a_name(tmp_path):
    with pytest.raises(SceneError, match="scene file not found"):
        co.optimize(str(tmp_path / "missing.toml"), quiet=True)
    # deploy pays its line out by elements: refused by name, so it was loaded.
    with pytest.raises(ValueError, match=r"^winch\.line: optimize works on a fixed number"):
        co.optimize("deploy", quiet=True)
    with pytest.raises(ValueError, match=r"scene 'paper_flat' has no \[lowering\] table"):
        co.land(Path("paper_flat.toml"))


def test_load_scene_takes_a_bundled_name_and_suggests_close_ones():
    """co.load_scene("deploy") loads the bundled scene the command line accepts (issue 45 item 10);
    a mistyped name names the closest bundled ones."""
    assert co.load_scene("deploy").name == "deploy"
    assert co.load_scene("deep_lift.toml").name == "deep_lift"
    with pytest.raises(SceneError, match=r"did you mean small_tow\?"):
        co.load_scene("smal_tow")
