"""``co.load_result`` reads every kind of result, by the kind the file declares (issue 45 item 5):
a line run (``[winch.line]``) in a results folder or under any name, ``cable-ocp lower``'s
landing run, an optimum under another name; what is not a result is named."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import MODELS, made_optimum

import cable_ocp as co
from cable_ocp import result_files
from cable_ocp.simulation.line_trajectory import LineTrajectory

LINE = {"element_length": 10.0, "pay_out_max": 30.0}


@pytest.fixture(scope="module")
def line_run():
    """20 m paid out over 12 s (0.5 m drum): a LineTrajectory of several segments."""
    scene = co.load_scene(
        MODELS / "paper_flat.toml",
        {"top.motion": "fixed", "cable.length": 50.0, "numerics.duration": 12.0,
         "numerics.constraint_tolerance": 1e-4, "winch.knots": 4, "winch.line": LINE,
         "end.payload": {"mass": 2000.0, "volume": 0.256}},
    )  # fmt: skip
    run = co.simulate(scene, winch=[10.0, 20.0, 30.0, 40.0], quiet=True)
    assert isinstance(run, LineTrajectory) and len(run.segments) > 1
    return run


def _same_line(loaded, run) -> None:
    assert isinstance(loaded, LineTrajectory)
    np.testing.assert_array_equal(loaded.element_count, run.element_count)
    np.testing.assert_array_equal(loaded.end, run.end)


def test_a_line_runs_folder_and_its_file_load(tmp_path, line_run):
    folder = tmp_path / "run"
    folder.mkdir()
    line_run.save(folder / "trajectory")
    for given in (folder, folder / "trajectory.nc", folder / "trajectory"):
        _same_line(co.load_result(given), line_run)


def test_a_landing_folder_and_a_result_under_any_name_load(tmp_path, line_run):
    """``lower``'s folder holds its run as landing.nc (and its other results under their own
    names); a file is read by the kind it declares, not by its name."""
    line_run.save(tmp_path / "landing")
    _same_line(co.load_result(tmp_path), line_run)
    _same_line(co.load_result(tmp_path / "landing.nc"), line_run)
    run = co.simulate(co.load_scene(MODELS / "hanging.toml", {"numerics.duration": 1.0}))
    result_files.save(run, tmp_path / "hover_optimised.nc")
    loaded = co.load_result(tmp_path / "hover_optimised.nc")
    assert isinstance(loaded, co.Trajectory) and loaded.omega == run.omega


def test_what_is_not_a_result_is_named(tmp_path):
    with pytest.raises(ValueError, match=r"no cable_ocp result there \(expected a folder"):
        co.load_result(tmp_path)
    with pytest.raises(ValueError, match=r"nothing: no such file or folder"):
        co.load_result(tmp_path / "nothing")
    (tmp_path / "sweep.nc").write_bytes(b"")
    with pytest.raises(ValueError, match=r"sweep\.nc: not a sweep's cases"):
        co.load_result(tmp_path)
    (tmp_path / "notes.nc").write_text("not netCDF")
    with pytest.raises(ValueError, match=r"notes\.nc: not a readable netCDF file"):
        co.load_result(tmp_path / "notes.nc")
    import xarray as xr

    xr.Dataset({"a": ("x", [1.0])}).to_netcdf(tmp_path / "other.nc")
    with pytest.raises(ValueError, match=r"other\.nc: not a cable_ocp result"):
        co.load_result(tmp_path / "other.nc")
    xr.Dataset(attrs={"cable_ocp_result": "Tide"}).to_netcdf(tmp_path / "tide.nc")
    with pytest.raises(ValueError, match=r"holds a Tide, which load_result does not read \(it "
                       r"reads .*LandingPlan, LandingResult, HoldResult\)"):  # fmt: skip
        co.load_result(tmp_path / "tide.nc")
    xr.Dataset(attrs={"cable_ocp_result": "HoldResult"}).to_netcdf(tmp_path / "hold.nc")
    with pytest.raises(ValueError, match=r"hold\.nc: not a readable hold \(cable_ocp_format"):
        co.load_result(tmp_path / "hold.nc")


def test_a_files_groups_read_at_once_are_those_read_one_by_one(tmp_path, line_run):
    """netcdf.read_groups opens the file once for all its groups (0.5 s an open for a line run of
    100 segments), with read's checks; a group the file lacks is named."""
    from cable_ocp.result_files import netcdf

    path = line_run.save(tmp_path / "line")
    names = [None, "segment_0", "segment_1"]
    together = netcdf.read_groups(path, "LineTrajectory", names)
    for name, dataset in zip(names, together, strict=True):
        assert dataset.equals(netcdf.read(path, "LineTrajectory", name)), name
    with pytest.raises(ValueError, match=r"line\.nc: not a readable netCDF file .*segment_7"):
        netcdf.read_groups(path, "LineTrajectory", ["segment_7"])
    with pytest.raises(ValueError, match=r"line\.nc: holds a LineTrajectory, not a Trajectory"):
        netcdf.read_groups(path, "Trajectory", ["segment_0"])


def test_every_result_of_a_lower_folder_loads(tmp_path, capsys):
    """cable-ocp lower's folder: its landing run, its landings from the hover and its hold, each
    read by co.load_result as what it is (14 s with the compile cache warm)."""
    from test_lowering import HEAVING, LOWERING, toml_value

    from cable_ocp import cli

    sets = [f"{key}={toml_value(value)}" for key, value in {**LOWERING, **HEAVING}.items()]
    out = tmp_path / "lowered"
    args = ["lower", str(MODELS / "paper_flat.toml"), "--out", str(out), "--quiet"]
    assert cli.main([*args, *(part for s in sets for part in ("--set", s))]) in (0, 3)
    capsys.readouterr()
    assert isinstance(co.load_result(out), LineTrajectory)  # landing.nc
    kinds = {name: type(co.load_result(out / name)).__name__
             for name in ("hover_optimised.nc", "hover_closed_loop.nc", "hold.nc")}  # fmt: skip
    assert kinds == {"hover_optimised.nc": "OcpResult", "hover_closed_loop.nc": "MpcResult",
                     "hold.nc": "MpcResult"}  # fmt: skip


def test_a_path_that_is_not_a_path_is_a_type_error():
    for given in (12, None, ["run"]):
        with pytest.raises(TypeError, match="load_result: path must be a result folder's or "):
            co.load_result(given)


@pytest.fixture(scope="module")
def plan():
    """test_lowering's 2 t load landed in open loop in still water (about 10 s)."""
    from test_lowering import lowering_scene

    return co.plan_landing(lowering_scene())


def test_a_landing_plan_round_trips_and_a_forged_part_is_refused(tmp_path, plan):
    """Saved, read back by co.load_result, every part restored; a part of another kind than its
    field allows, or a part the plan does not have, is refused naming it (issue 41)."""
    import netCDF4

    from cable_ocp.lowering.plan import LandingPlan
    from cable_ocp.result_files.dataset import fields_equal

    path = plan.save(tmp_path / "plan.nc")
    loaded = co.load_result(path)
    assert isinstance(loaded, LandingPlan) and loaded.status == plan.status
    assert loaded.scene.to_dict() == plan.scene.to_dict()
    for name in ("descent", "report", "hold"):
        assert fields_equal(getattr(loaded, name), getattr(plan, name)), name
    _same_line(loaded.run, plan.run)
    t = np.linspace(0.0, plan.scene.numerics.duration, 7)
    np.testing.assert_array_equal(loaded.angle(t)[0], plan.angle(t)[0])
    replayed = co.simulate(loaded.scene, winch=loaded)  # as any result with a winch replays
    np.testing.assert_allclose(replayed.end, plan.run.end, rtol=0, atol=1e-9)
    with netCDF4.Dataset(path, "a") as root:
        root["report"].setncattr("cable_ocp_result", "HoldCorrection")
    with pytest.raises(ValueError, match="report: holds a HoldCorrection, expected LandingReport"):
        co.load_result(path)
    path = plan.save(tmp_path / "other.nc")
    with netCDF4.Dataset(path, "a") as root:
        root.setncattr("parts", '["descent", "mpc"]')
    with pytest.raises(ValueError, match="parts: mpc is not a part of a LandingPlan"):
        co.load_result(path)


def test_a_plan_whose_model_failed_round_trips_without_its_run(tmp_path, plan):
    from dataclasses import replace

    failed = replace(plan, run=None, report=None, failure="the model blew up")
    loaded = co.load_result(failed.save(tmp_path / "failed.nc"))
    assert loaded.run is None and loaded.report is None and loaded.status == failed.status


def test_an_optimum_saves_to_a_file_or_a_folder_and_loads_from_either(tmp_path):
    """save(path)/load(path) as every result has them: a ``.nc`` file, or a results folder."""

    from cable_ocp.control.optimization import OcpResult

    run = co.simulate(co.load_scene("hanging").updated({"numerics.duration": 1.0}))
    optimum = made_optimum(run)
    in_folder = optimum.save(tmp_path / "run")
    as_file = optimum.save(tmp_path / "elsewhere" / "best.nc")
    assert in_folder == tmp_path / "run" / "result.nc" and as_file.name == "best.nc"
    for path in (tmp_path / "run", in_folder, as_file):
        assert OcpResult.load(path).omega == run.omega
        assert co.load_result(path).omega == run.omega
