"""The scene fields of axial elasticity (issue 44): EA, fill factor, axial damping, model.axial."""

import math
import subprocess
import sys

import pytest

from cable_ocp.scene.schema import Cable, ModelOptions, SceneError, scene_from_dict

SCENE = {"model": {"elements": 5}, "top": {}, "numerics": {"duration": 10.0, "step": 0.05}}


def test_defaults_keep_the_solid_section_and_auto():
    scene = scene_from_dict(SCENE)
    cable = scene.cable
    assert cable.axial_stiffness is None and cable.fill_factor == 1.0
    assert cable.axial_damping == 0.02 and scene.model.axial == "auto"
    assert cable.axial_stiffness_value == pytest.approx(1e11 * math.pi * 0.07**2 / 4)


def test_derived_axial_stiffness_is_e_a_f():
    cable = Cable(diameter=0.04, youngs_modulus=2e11, area=8e-4, fill_factor=0.6)
    assert cable.axial_stiffness_value == pytest.approx(2e11 * 8e-4 * 0.6)
    assert Cable(axial_stiffness=3.5e7).axial_stiffness_value == 3.5e7


def test_axial_fields_round_trip():
    data = {**SCENE, "cable": {"axial_stiffness": 1e8, "axial_damping": 0.05}}
    data["model"] = {"elements": 5, "axial": "elastic"}
    scene = scene_from_dict(data)
    assert scene_from_dict(scene.to_dict()) == scene
    assert scene.model.axial == "elastic" and scene.cable.axial_damping == 0.05


@pytest.mark.parametrize(
    ("table", "values", "path", "rule"),
    [
        ("cable", {"axial_stiffness": 0.0}, "cable.axial_stiffness", "> 0 (N)"),
        ("cable", {"axial_stiffness": -1e6}, "cable.axial_stiffness", "> 0 (N)"),
        ("cable", {"fill_factor": 0.05}, "cable.fill_factor", ">= 0.1 and <= 1"),
        ("cable", {"fill_factor": 1.2}, "cable.fill_factor", ">= 0.1 and <= 1"),
        ("cable", {"axial_damping": -0.01}, "cable.axial_damping", ">= 0 and <= 1"),
        ("cable", {"axial_damping": 1.5}, "cable.axial_damping", ">= 0 and <= 1"),
        ("model", {"axial": "stretchy"}, "model.axial", "'rigid', 'elastic', 'auto'"),
    ],
)
def test_out_of_range_refused_naming_the_field(table, values, path, rule):
    data = {**SCENE, table: {**SCENE.get(table, {}), **values}}
    with pytest.raises(SceneError) as caught:
        scene_from_dict(data)
    assert caught.value.path == path
    assert rule in str(caught.value)


def test_axial_stiffness_and_fill_factor_together_refused_naming_both():
    with pytest.raises(SceneError, match=r"cable\.fill_factor = 0\.7.*cable\.axial_stiffness"):
        Cable(axial_stiffness=1e8, fill_factor=0.7)
    assert Cable(axial_stiffness=1e8, fill_factor=1.0).axial_stiffness_value == 1e8


def test_model_axial_expects_a_string():
    with pytest.raises(SceneError, match=r"model\.axial: expected a string"):
        ModelOptions(axial=True)


def test_schema_lists_the_axial_fields():
    out = subprocess.run(
        [sys.executable, "-m", "cable_ocp.cli", "schema", "cable"],
        capture_output=True, text=True, check=True,
    ).stdout  # fmt: skip
    for name in ("cable.axial_stiffness", "cable.fill_factor", "cable.axial_damping"):
        assert name in out
    assert "default 0.02" in out and ">= 0.1 and <= 1" in out
