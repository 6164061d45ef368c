import dataclasses
import math
import shutil
from pathlib import Path

import pytest

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

from cable_ocp.scene.schema import (
    REQUIRED_TABLES,
    Cable,
    Hill,
    Numerics,
    Scene,
    SceneError,
    Seabed,
    load_scene,
    scene_from_dict,
)

MODELS = Path(__file__).resolve().parent.parent / "models"
SCENES = ["catenary", "paper_flat", "paper_hill", "end_force", "hanging"]
BUNDLED = sorted(p.stem for p in MODELS.glob("*.toml"))
HILL = {"height": 15.0, "x0": 70.0, "y0": 20.0, "width_x": 20.0, "width_y": 20.0}


@pytest.fixture(scope="module")
def flat() -> Scene:
    return load_scene(MODELS / "paper_flat.toml")


@pytest.mark.parametrize("name", SCENES)
def test_bundled_scene_loads_and_round_trips(name):
    scene = load_scene(MODELS / f"{name}.toml")
    assert scene.name == name
    assert scene.source == str((MODELS / f"{name}.toml").resolve())
    assert scene_from_dict(scene.to_dict()) == scene
    assert hash(scene_from_dict(scene.to_dict())) == hash(scene)


def test_scene_values():
    cat = load_scene(MODELS / "catenary.toml")
    assert cat.cable.cross_section_area == pytest.approx(0.07**2 / 4)
    assert cat.end.force == (20000.0, 0.0, 50000.0)
    assert not cat.environment.submerged and not cat.model.bending
    hill = load_scene(MODELS / "paper_hill.toml")
    assert hill.seabed.hills == (Hill(**HILL),)
    assert hill.top.motion == "tow" and hill.segment_length == 20.0
    end = load_scene(MODELS / "end_force.toml")
    assert end.model.elements == 100 and end.end.force_period == (0.0, 50.0, 0.0)
    assert load_scene(MODELS / "hanging.toml").end.force == (0.0, 0.0, 0.0)


def test_defaults_and_derived_properties():
    cable = Cable()
    assert cable.cross_section_area == pytest.approx(math.pi * 0.07**2 / 4)
    assert cable.mass_per_length == pytest.approx(6500 * math.pi * 0.07**2 / 4)
    assert cable.bending_stiffness == pytest.approx(1e11 * math.pi * 0.07**4 / 64)
    assert cable.torsional_stiffness == pytest.approx(8e10 * math.pi * 0.07**4 / 32)
    assert scene_from_dict({}) == Scene()
    assert Scene().to_dict()["seabed"]["hills"] == []
    assert isinstance(Cable(length=300).length, float)


def test_overrides(flat):
    scene = load_scene(MODELS / "paper_flat.toml", {"model.elements": 30, "numerics.step": 0.01})
    assert scene.model.elements == 30 and scene.numerics.step == 0.01
    # The winch keeps its reach at n = 30: the top element stays 10 m long, the rest is graded.
    assert scene.top_element_length == 10.0
    assert scene.segment_length == pytest.approx(290.0 / 29.5, rel=1e-15)
    assert flat.updated({"model.elements": 30, "numerics.step": 0.01}) == scene
    assert flat.updated({"seabed.hills": [HILL]}).seabed.hills == (Hill(**HILL),)
    assert flat.updated({"name": "x"}).name == "x"
    assert flat.updated({}).source == flat.source
    with pytest.raises(ValueError, match=r"^numerics\.step = -1\.0 is out of range"):
        flat.updated({"numerics.step": -1})
    with pytest.raises(ValueError, match=r"^cable\.lenght: unknown key; allowed keys: length"):
        load_scene(MODELS / "paper_flat.toml", {"cable.lenght": 3.0})
    with pytest.raises(ValueError, match=r"^cable\.length\.x: cannot set"):
        flat.updated({"cable.length.x": 1.0})
    # A table given as a value is copied: a later dotted key into it leaves the caller's alone.
    table = {"land_time": 50.0, "height": 5.0}
    lowered = flat.updated({"lowering": table, "lowering.height": 7.0})
    assert lowered.lowering.height == 7.0 and table == {"land_time": 50.0, "height": 5.0}


def test_direct_construction_is_validated(flat):
    with pytest.raises(ValueError, match=r"^cable\.diameter = -1\.0 is out of range: must be > 0"):
        dataclasses.replace(flat.cable, diameter=-1.0)
    with pytest.raises(ValueError, match=r"^numerics\.step = 2\.0 .* <= numerics\.duration"):
        Numerics(duration=1.0, step=2.0)
    with pytest.raises(ValueError, match=r"^winch\.angle_min"):
        dataclasses.replace(flat, cable=Cable(length=20.0))
    with pytest.raises(ValueError, match=r"^seabed\.hills\[0\]: expected a Hill"):
        Seabed(hills=(HILL,))
    with pytest.raises(ValueError, match=r"^hill\.width_x"):
        Hill(**{**HILL, "width_x": 0.0})


def test_table_motion(tmp_path, flat):
    (tmp_path / "vessel.csv").write_text("t,x,y,z\n0,0,0,0\n")
    data = flat.to_dict()
    data["top"] = {"motion": "table", "table": {"file": "vessel.csv"}}
    scene = scene_from_dict(data, base_dir=tmp_path)
    assert scene.top.table.file == str((tmp_path / "vessel.csv").resolve())
    assert scene_from_dict(scene.to_dict()) == scene
    (tmp_path / "s.toml").write_text(
        '[model]\n[numerics]\n[top]\nmotion = "table"\n[top.table]\nfile = "vessel.csv"\n'
    )
    assert load_scene(tmp_path / "s.toml").top.table == scene.top.table


def test_invalid_toml(tmp_path):
    (tmp_path / "bad.toml").write_text("[cable\n")
    with pytest.raises(ValueError, match="invalid TOML"):
        load_scene(tmp_path / "bad.toml")


BAD = [
    # unknown keys
    ({"colour": "red"}, r"^colour: unknown key; allowed keys: name, description, cable"),
    ({"cable.lenght": 3.0}, r"^cable\.lenght: unknown key; allowed keys: length, diameter"),
    ({"seabed.hills": [{**HILL, "hieght": 1.0}]}, r"^seabed\.hills\[0\]\.hieght: unknown key"),
    ({"seabed.hills": [{"height": 1.0}]}, r"^seabed\.hills\[0\]\.x0: missing required key"),
    ({"cable": 3}, r"^cable: expected a table, got int 3"),
    # wrong types
    ({"cable.length": "300"}, r"^cable\.length: expected a number, got str '300'"),
    ({"environment.gravity": True}, r"^environment\.gravity: expected a number, got bool"),
    ({"model.elements": 15.5}, r"^model\.elements: expected an integer, got float 15\.5"),
    ({"model.elements": 15.0}, r"^model\.elements: expected an integer, got float 15\.0"),
    ({"model.torsion": 1}, r"^model\.torsion: expected true or false, got int 1"),
    ({"environment.current": [0.0, 0.0]}, r"^environment\.current: expected 3 numbers"),
    ({"environment.current": 1.0}, r"^environment\.current: expected 3 numbers"),
    ({"end.force": [0.0, "x", 0.0]}, r"^end\.force\[1\]: expected a number"),
    ({"cable.length": math.nan}, r"^cable\.length = nan is out of range: must be finite"),
    # out of range
    ({"cable.length": -3.0}, r"^cable\.length = -3\.0 is out of range: must be > 0 \(m\)"),
    ({"cable.diameter": -0.07}, r"^cable\.diameter = -0\.07 is out of range: must be > 0 \(m\)"),
    ({"model.elements": 0}, r"^model\.elements = 0 is out of range: must be >= 1 and <= 1000"),
    ({"numerics.step": 0.0}, r"^numerics\.step = 0\.0 is out of range: must be > 0 \(s\)"),
    ({"numerics.step": -0.01}, r"^numerics\.step = -0\.01 is out of range"),
    ({"numerics.step": 300.0}, r"^numerics\.step = 300\.0 .* <= numerics\.duration = 210\.0"),
    ({"numerics.baumgarte_alpha": -1.0}, r"^numerics\.baumgarte_alpha = -1\.0 .* >= 0 \(1/s\)"),
    ({"numerics.baumgarte_beta": -1.0}, r"^numerics\.baumgarte_beta = -1\.0 .* >= 0 \(1/s\)"),
    ({"winch.angle_min": 1.0}, r"^winch\.angle_min = 1\.0 is out of range: must be <= 0"),
    ({"winch.angle_max": -1.0}, r"^winch\.angle_max = -1\.0 is out of range: must be >= 0"),
    ({"winch.angle_min": 0.0, "winch.angle_max": 0.0}, r"^winch\.angle_min .* < winch\.angle_max"),
    ({"winch.top_length_min": 145.0}, r"^winch\.angle_min = -16\.0 .* over half the cable"),
    ({"winch.top_length_max": 8.0}, r"^winch\.top_length_max = 8\.0 .* at phi = 0, .* = 10\.0"),
    ({"winch.angle_min": -300.0}, r"^winch\.angle_min = -300\.0 .* > .* = -296\.0 .*\(rad\)$"),
    ({"winch.top_length_max": 1.0}, r"^winch\.top_length_max .* > winch\.top_length_min"),
    ({"end.force_period": [0.0, -1.0, 0.0]}, r"^end\.force_period\[1\] = -1\.0 .* >= 0 \(s\)"),
    ({"environment.water_density": 0.0}, r"^environment\.water_density = 0\.0 .* when"),
    ({"seabed.hills": [{**HILL, "width_x": 0.0}]}, r"^seabed\.hills\[0\]\.width_x = 0\.0 .* > 0"),
    ({"hydrodynamics.quadrature_points": 0}, r"^hydrodynamics\.quadrature_points = 0 .* >= 1"),
    ({"hydrodynamics.quadrature_points": 9}, r"^hydrodynamics\.quadrature_points = 9 .* <= 8"),
    # huge numbers, a light cable, too many steps, derived values that overflow
    ({"model.elements": 10**400}, r"^model\.elements = 1000000000.*\(401 characters\) is out of"),
    ({"cable.length": 10**400}, r"^cable\.length = 1000000000.* is out of range: must be finite"),
    ({"cable.length": math.inf}, r"^cable\.length = inf is out of range: must be finite"),
    ({"model.elements": math.inf}, r"^model\.elements: expected an integer, got float inf"),
    (
        {"cable.density": 500.0},
        r"^cable\.density = 500\.0 kg/m\^3 is not denser than environment\.water_density = "
        r"1025\.0 kg/m\^3: the rope's buoyancy \(606\.1 kg\) must be outweighed",
    ),
    ({"cable.density": 1025.0}, r"^cable\.density = 1025\.0 kg/m\^3 is not denser"),
    ({"numerics.step": 1e-300}, r"^numerics\.step = 1e-300 .* >= numerics\.duration / 1e\+08"),
    ({"cable.diameter": 1e200}, r"^cable: cross_section_area overflows \(diameter = 1e\+200 m"),
    ({"cable.youngs_modulus": 1e308}, r"^cable: bending_stiffness overflows"),
    # top motion
    ({"top.motion": "towing"}, r"^top\.motion = 'towing' is not allowed: must be one of 'fixed'"),
    ({"top.motion": "table"}, r"^top\.table: required when top\.motion = 'table'"),
    (
        {"top.motion": "table", "top.table.file": "missing.csv"},
        r"^top\.table\.file = '.*missing\.csv'",
    ),
    (
        {"top.motion": "fixed", "top.tow.surge_speed": 1.0},
        r"^top\.tow: given, but top\.motion = 'fixed' does not use it",
    ),
    ({"top.surge_speed": 1.0}, r"^top\.surge_speed: unknown key; allowed keys: motion, start, tow"),
    ({"top.heave.period": 8.0}, r"^top\.heave\.amplitude: missing required key"),
]


@pytest.mark.parametrize(("overrides", "message"), BAD)
def test_rejected(flat, overrides, message):
    with pytest.raises(SceneError, match=message):
        load_scene(MODELS / "paper_flat.toml", overrides)
    with pytest.raises(ValueError, match=message):
        flat.updated(overrides)


def test_air_needs_no_water_density(flat):
    scene = flat.updated({"environment.submerged": False, "environment.water_density": 0.0})
    assert scene.environment.water_density == 0.0


def test_light_cable_is_fine_in_air(flat):
    scene = flat.updated({"environment.submerged": False, "cable.density": 500.0})
    assert scene.cable.density == 500.0


def test_every_bundled_scene_file_has_the_required_tables():
    for path in MODELS.glob("*.toml"):
        data = tomllib.loads(path.read_text())
        assert set(REQUIRED_TABLES) <= set(data), path.name


def _write(path, content):
    if isinstance(content, bytes):
        path.write_bytes(content)
    else:
        path.write_text(content)
    return path


FILE_ERRORS = [
    ("", r"s\.toml: empty scene file; a scene file needs at least the tables \[model\], \[top\]"),
    ("# only a comment\n", r"s\.toml: empty scene file"),
    ("[model]\n[top]\n", r"^numerics: missing table \[numerics\] in .*s\.toml; a scene file needs"),
    ("[top]\n[numerics]\n", r"^model: missing table \[model\]"),
    ("[model]\n[numerics]\n[cable]\nlength = 3", r"^top: missing table \[top\]"),
    (b"[model]\n[top]\n[numerics]\nname = '\xff'\n", r"s\.toml: not a UTF-8 text file \(byte 33\)"),
    ("[model]\nelements = 3\nelements = 4\n", r"s\.toml: invalid TOML: Cannot overwrite a value"),
    ("[model]\nelements = " + "9" * 5000 + "\n", r"s\.toml: invalid TOML: Exceeds the limit"),
    ("a = " + "[" * 5000 + "]" * 5000, r"s\.toml: invalid TOML"),
]


@pytest.mark.parametrize(("content", "message"), FILE_ERRORS)
def test_unreadable_or_incomplete_files_are_scene_errors(tmp_path, content, message):
    with pytest.raises(SceneError, match=message):
        load_scene(_write(tmp_path / "s.toml", content))


def test_missing_file_and_folder_are_scene_errors(tmp_path):
    with pytest.raises(SceneError, match=r"nothing\.toml: scene file not found$"):
        load_scene(tmp_path / "nothing.toml")
    with pytest.raises(SceneError, match=r": is a folder, not a scene file$"):
        load_scene(tmp_path)


def test_the_three_required_tables_are_enough(tmp_path):
    scene = load_scene(_write(tmp_path / "s.toml", "[model]\n[top]\n[numerics]\n"))
    assert scene == Scene(name="s", source=str(tmp_path / "s.toml"))


@pytest.mark.parametrize("name", BUNDLED)
def test_scene_mutants_load_or_raise_scene_error(tmp_path, mutants, name, models_dir):
    """Mutants of the bundled scene files load to a valid scene or raise SceneError, nothing else.

    The mutations must exercise both outcomes: more than half of them refused, some loaded. The
    data files the scenes name (bathymetry grids) lie beside the mutants as beside the scenes.
    """
    shutil.copytree(models_dir / "data", tmp_path / "data")
    refused, loaded, wrong = 0, 0, []
    for k, (text, what) in enumerate(mutants(name)):
        path = tmp_path / f"mutant_{k}.toml"
        path.write_bytes(text)
        try:
            scene = load_scene(path)
        except SceneError as error:
            assert str(error), what
            refused += 1
            continue
        except Exception as error:  # the failure this test looks for
            wrong.append(f"{what}: {type(error).__name__}: {error}")
            continue
        assert isinstance(scene, Scene)
        assert scene_from_dict(scene.to_dict(), name=scene.name) == scene, what
        loaded += 1
    assert wrong == []
    assert refused > (refused + loaded) // 2 and loaded > 0


@pytest.mark.parametrize("overrides", [["model.elements"], "model.elements=20", 20])
def test_overrides_that_are_no_mapping_are_a_type_error_naming_them(overrides):
    with pytest.raises(TypeError, match=r"^overrides: expected a mapping of dotted field paths"):
        load_scene(MODELS / "hanging.toml", overrides)
