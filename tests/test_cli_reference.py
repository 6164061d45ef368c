"""``cable-ocp scenes``, ``cable-ocp schema [KEY]``, bundled scene names wherever a scene file is
asked for, and the schema's rows (every number has a unit or is declared dimensionless)."""

from __future__ import annotations

import dataclasses

import pytest

from cable_ocp import cli
from cable_ocp.scene.bundled import scene_argument, scene_names, scene_path
from cable_ocp.scene.fields import all_rows, field_rows, rows_under
from cable_ocp.scene.schema import Cable, _param, load_scene


def test_scenes_lists_every_bundled_scene_with_what_it_is(capsys):
    assert cli.main(["scenes"]) == 0
    lines = capsys.readouterr().out.splitlines()
    for name in scene_names():
        line = next(line for line in lines if line.split()[0] == name)
        assert len(line.split(maxsplit=1)[1]) > 20, line  # the file's own first line
    assert "option B of the paper" in next(line for line in lines if line.startswith("paper_hill"))


def test_schema_of_a_field_prints_its_default_unit_range_and_meaning(capsys):
    assert cli.main(["schema", "cable.diameter"]) == 0
    out = capsys.readouterr().out
    assert out.splitlines()[0].split() == ["cable.diameter", "float,", "default", "0.07", "m"]
    assert "range: > 0" in out and "Diameter d." in out


def test_schema_of_a_section_prints_every_field_under_it(capsys):
    assert cli.main(["schema", "top.tow"]) == 0
    paths = [line.split()[0] for line in capsys.readouterr().out.splitlines()
             if not line.startswith(" ")]  # fmt: skip
    assert paths == [row["path"] for row in rows_under("top.tow")]
    assert "top.tow.surge_speed" in paths and all(p.startswith("top.tow") for p in paths)


def test_schema_of_an_unknown_key_names_it_and_the_sections(capsys):
    assert cli.main(["schema", "cabel.diameter"]) == 2
    err = capsys.readouterr().err
    assert "schema key 'cabel.diameter' names no scene field" in err
    assert "cable, " in err and "winch" in err


def test_every_scene_field_has_a_unit_a_range_and_a_meaning():
    rows = all_rows()
    assert len(rows) > 50
    assert not [row["path"] for row in rows if row["missing"]]
    assert all(row["unit"] and row["range"] and row["meaning"] for row in rows)
    # The top level's fields, a section's and a nested section's are rows.
    paths = {row["path"] for row in rows}
    assert {"name", "cable.density", "top.heave.sea_state.significant_height"} <= paths


def test_a_number_declared_without_a_unit_is_caught():
    """The rows' check names a new numeric field that has no unit and is not dimensionless."""

    @dataclasses.dataclass(frozen=True)
    class Probe:
        length: float = _param(1.0, doc="Length.", gt=0, unit="m")
        stretch: float = _param(1.0, doc="A number without a unit.", gt=0)
        name: str = _param("x", kind="str", doc="A name.")

    rows = {row["field"]: row for row in field_rows(Probe, "probe")}
    assert rows["length"]["missing"] == "" and rows["length"]["unit"] == "m"
    assert rows["stretch"]["missing"] == "a unit"
    assert rows["name"]["missing"] == "" and rows["name"]["unit"] == "—"
    assert all(not row["missing"] for row in field_rows(Cable, "cable"))


def test_a_bundled_name_stands_for_its_file_and_a_file_wins(tmp_path, monkeypatch):
    assert scene_argument("paper_hill") == scene_path("paper_hill")
    assert scene_argument("paper_hill.toml") == scene_path("paper_hill")
    monkeypatch.chdir(tmp_path)
    (tmp_path / "paper_hill.toml").write_text('name = "mine"\n')
    assert scene_argument("paper_hill.toml").resolve() == (tmp_path / "paper_hill.toml")
    # Neither a file nor a bundled name: the path as given, which loading reports as missing.
    assert str(scene_argument("nowhere.toml")) == "nowhere.toml"
    assert str(scene_argument("sub/paper_hill.toml")) == "sub/paper_hill.toml"


def test_a_command_runs_a_bundled_scene_by_name(tmp_path, capsys):
    out = tmp_path / "run"
    code = cli.main(["simulate", "hanging", "--out", str(out), "--quiet",
                     "--set", "numerics.duration=2.0"])  # fmt: skip
    assert code == 0, capsys.readouterr().err
    assert (out / "trajectory.nc").is_file()
    assert load_scene(scene_path("hanging")).name == "hanging"


def test_a_missing_scene_is_refused_in_one_line(tmp_path, capsys):
    assert cli.main(["simulate", "no_such_scene", "--out", str(tmp_path / "x")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("cable-ocp simulate: error:") and "no_such_scene" in err
    assert len(err.splitlines()) == 1


@pytest.mark.parametrize("command", ["simulate", "optimize", "mpc"])
def test_the_help_says_a_name_is_taken(command, capsys):
    assert cli.main([command, "--help"]) == 0
    assert "bundled scene's name" in " ".join(capsys.readouterr().out.split())


def test_optimize_writes_its_summary_and_the_winch_table(tmp_path, capsys):
    """summary.json holds the result's figures; winch.csv the verified profile, whose line out
    and pay-out rate are the drum's r_D phi and r_D phi' (checked against the result's own
    trajectory, and the rate against a finite difference of the angle)."""
    import json

    import numpy as np

    from cable_ocp.control.optimization import OcpResult

    out = tmp_path / "o"
    assert cli.main(["optimize", "small_tow", "--out", str(out), "--quiet"]) == 0, (
        capsys.readouterr().err
    )
    summary = json.loads((out / "summary.json").read_text())
    result = OcpResult.load(out)
    assert summary["scene"] == "small_tow" and summary["success"] is True
    assert summary["omega"] == pytest.approx(result.omega, rel=1e-12)
    assert summary["locked_omega"] > 10 * summary["omega"]
    table = np.genfromtxt(out / "winch.csv", delimiter=",", names=True)
    scene = load_scene(scene_path("small_tow"))
    radius = scene.winch.drum_radius
    np.testing.assert_allclose(table["time_s"], result.trajectory.time, atol=1e-9)
    np.testing.assert_allclose(table["winch_angle_rad"], result.trajectory.winch_angle, atol=1e-8)
    np.testing.assert_allclose(
        table["line_out_m"], scene.cable.length + radius * table["winch_angle_rad"], atol=1e-6
    )
    np.testing.assert_allclose(table["payout_rate_m_s"], radius * table["winch_rate_rad_s"])
    slope = np.gradient(table["winch_angle_rad"], table["time_s"])
    scale = np.max(np.abs(table["winch_rate_rad_s"]))
    assert np.max(np.abs(slope - table["winch_rate_rad_s"])) < 0.05 * scale
