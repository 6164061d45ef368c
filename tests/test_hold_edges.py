"""co.hold on a scene file's path, and a line whose joints agree only to rounding (issue 45)."""

import numpy as np
import pytest
import xarray as xr

import cable_ocp as co

SCENE = """
name = "small_lowering"
[cable]
length = 30.0
diameter = 0.04
density = 7850.0
[model]
elements = 3
[top]
motion = "fixed"
[end.payload]
mass = 1000.0
volume = 0.128
drag_area = 1.0
drag = 1.2
[winch]
drum_radius = 1.0
rate_max = 2.0
acceleration_max = 1.5
[winch.line]
pay_out_max = 30.0
haul_in_max = 0.0
element_length = 10.0
[seabed]
clearance = 5.0
minimum_clearance = 2.0
[seabed.grid]
file = "flat50.nc"
[lowering]
land_time = 60.0
height = 5.0
tension_min = 1000.0
tension_max = 100000.0
[numerics]
duration = 80.0
step = 0.05
output_every = 10
"""


def test_a_hold_takes_a_scene_files_path_and_a_line_out_equal_to_rounding(tmp_path):
    """The reduced model's top joint at 30.000000000000007 m against the plant's
    30.000000000000004 m is the same joint (it was refused as 'beyond' it, after the work)."""
    axis = np.arange(-200.0, 201.0, 5.0)
    flat = xr.Dataset(
        {"elevation": (("x", "y"), np.full((axis.size, axis.size), -50.0))},
        coords={"x": axis, "y": axis},
    )
    flat.to_netcdf(tmp_path / "flat50.nc")  # 50 m deep
    path = tmp_path / "small_lowering.toml"
    path.write_text(SCENE)
    held = co.hold(str(path))
    assert held.success, held.status
    assert held.deviation < 1e-6
    assert co.hold(path, line_out=50.0).success


def test_lower_writes_everything_when_a_closed_loop_stops_before_its_landing(
    tmp_path, capsys, monkeypatch
):
    """A plant that fails at its first sample leaves no samples near the landing: the figure is
    drawn on what ran, every file is written, and the command exits 3 (it raised on np.ptp).

    The plant fails on a 1e-12 m bond tolerance at its own step (at h / 64 it would hold it)."""
    from cable_ocp import cli
    from cable_ocp.control.closed_loop import plant

    monkeypatch.setattr(plant, "SUBSTEPS", (1,))

    axis = np.arange(-200.0, 201.0, 5.0)
    deep = np.full((axis.size, axis.size), -100.0)
    xr.Dataset({"elevation": (("x", "y"), deep)}, coords={"x": axis, "y": axis}).to_netcdf(
        tmp_path / "flat100.nc"
    )
    scene = SCENE.replace('"flat50.nc"', '"flat100.nc"').replace(
        "pay_out_max = 30.0", "pay_out_max = 80.0"
    )
    scene = scene.replace("land_time = 60.0", "land_time = 100.0").replace(
        "duration = 80.0", "duration = 130.0"
    )
    path = tmp_path / "lw2.toml"
    path.write_text(scene)
    out = tmp_path / "out"
    code = cli.main(["lower", str(path), "--set", "numerics.constraint_tolerance=1e-12",
                     "--out", str(out), "--quiet"])  # fmt: skip
    assert code == 3
    assert "the closed-loop landing from the hover failed" in capsys.readouterr().err
    assert (out / "hover_closed_loop.png").stat().st_size > 0 and (out / "summary.json").is_file()


def test_a_saved_hold_whose_figures_its_run_does_not_give_is_refused(tmp_path):
    """A hold's file is checked against its closed loop's run on load (a forged deviation, peak
    rate or band is named), and the genuine file loads."""
    import netCDF4

    axis = np.arange(-200.0, 201.0, 5.0)
    flat = np.full((axis.size, axis.size), -50.0)
    xr.Dataset({"elevation": (("x", "y"), flat)}, coords={"x": axis, "y": axis}).to_netcdf(
        tmp_path / "flat50.nc"
    )
    path = tmp_path / "small_lowering.toml"
    path.write_text(SCENE)
    genuine = co.hold(path).save(tmp_path / "hold.nc")
    assert co.load_result(genuine).success
    for name, value, message in (
        ("deviation", 3.0, r"deviation = 3"),
        ("peak_rate", 100.0, r"peak_rate = 100"),
        ("band", -1.0, r"band = -1\.0 m: expected a hold band > 0"),
    ):
        forged = tmp_path / f"{name}.nc"
        forged.write_bytes(genuine.read_bytes())
        with netCDF4.Dataset(forged, "a") as data:
            data.variables[name][...] = value
        with pytest.raises(ValueError, match=rf"{name}\.nc: .*{message}"):
            co.load_result(forged)
