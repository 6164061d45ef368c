"""Result files edited by hand are refused on load, not reported as if genuine (issue 45, D4).

A run's file is checked against its own series and its scene: the time axis (finite, strictly
increasing, from 0 to the scene's ``numerics.duration`` on its output grid), the scene record
(valid by the scene schema, and the scene the arrays were made with), and Omega recomputed by
eq. 39 from the stored ``e(t)``. Each case edits a genuine file in place with netCDF4 and expects
one ``ValueError`` naming the file, the variable and what was expected.
"""

from __future__ import annotations

import json
import shutil

import netCDF4
import numpy as np
import pytest
from conftest import MODELS, made_optimum

import cable_ocp as co
from cable_ocp.simulation.line_trajectory import LineTrajectory
from cable_ocp.simulation.trajectory import Trajectory


def _edit(path, change) -> None:
    with netCDF4.Dataset(path, "a") as dataset:
        change(dataset)


def _series(name, change):
    """An edit of the variable ``name``: ``change(values)`` returns the new values."""

    def edit(group):
        variable = group.variables[name]
        variable[...] = change(np.array(variable[...]))

    return edit


def _value(name, value):
    """An edit of the 0-d variable ``name``."""
    return lambda group: group.variables[name].assignValue(value)


def _scene(key, value, group=""):
    """An edit of the scene record: the dotted ``key`` set to ``value`` (in ``group``)."""

    def edit(dataset):
        where = dataset[group] if group else dataset
        record = json.loads(where.getncattr("scene_record"))
        section, _, field = key.partition(".")
        record[section][field] = value
        where.setncattr("scene_record", json.dumps(record))

    return edit


def _swapped(values):
    values[[3, 4]] = values[[4, 3]]
    return values


@pytest.fixture(scope="module")
def run_file(tmp_path_factory):
    """A towed run of 6 s on 5 elements, kept every 0.1 s: its clearance error is not zero."""
    scene = co.load_scene(
        MODELS / "paper_flat.toml",
        {"numerics.duration": 6.0, "model.elements": 5, "numerics.output_every": 2},
    )
    run = co.simulate(scene, quiet=True)
    assert run.omega > 0  # so that an edit of e(t) changes Omega
    return run.save(tmp_path_factory.mktemp("run") / "run")


def test_a_genuine_run_loads(run_file):
    run = Trajectory.load(run_file)
    assert run.time[-1] == 6.0 and run.tensions.shape[1] == 6


DURATION = r"expected its scene's numerics\.duration"
GRID = r"expected every numerics\.output_every \* numerics\.step"
INVALID = r"scene_record: not a valid scene"


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (_value("omega", 1e-3), r"omega = 0\.001 m: expected .* m, eq\. 39"),
        (_series("clearance_error", lambda e: 0.5 * e), r"omega = .* m: expected .* eq\. 39"),
        (_series("time", _swapped), r"time: not strictly increasing .* at index 4"),
        (_series("time", lambda t: np.where(t == t[5], np.nan, t)), r"time: not all finite"),
        (_series("time", lambda t: t + 0.2), r"time starts at 0\.2 s: expected 0 s"),
        (_series("time", lambda t: 1.5 * t), rf"time ends at 9 s: {DURATION} = 6\.0 s"),
        (_series("time", lambda t: t**2 / 6.0), rf"time: 61 samples .*: {GRID} = 0\.1 s"),
        (_scene("numerics.duration", 12.0), rf"time ends at 6 s: {DURATION} = 12\.0 s"),
        (_scene("numerics.step", 0.1), rf"time: 61 samples .*: {GRID} = 0\.2 s"),
        (_scene("model.elements", 9), r"6 elements \(n = 5\): expected .* model\.elements = 9"),
        (_scene("model.elements", -3), rf"{INVALID} \(model\.elements = -3 is out of range"),
        (_scene("cable.density", "heavy"), rf"{INVALID} \(cable\.density"),
    ],
)
def test_an_edited_run_file_is_refused(tmp_path, run_file, change, message):
    path = shutil.copy(run_file, tmp_path / "forged.nc")
    _edit(path, change)
    with pytest.raises(ValueError, match=r"forged\.nc: not a readable trajectory .*" + message):
        Trajectory.load(path)


def _in(group, edit):
    return lambda dataset: edit(dataset[group])


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (_in("segment_0", _value("omega", 0.5)), r"omega = 0\.5 m: expected"),
        (_in("segment_1", _value("omega", 0.5)), r"segment_1: omega = 0\.5 m: expected the run's"),
        (_in("segment_1", _series("clearance_error", lambda e: e + 1.0)), r"omega = .* eq\. 39"),
        (_in("segment_1", _series("time", lambda t: t + 5.0)), rf"ends at 17 s: {DURATION} = 12"),
        (_series("line_out", lambda v: v + 1.0), r"line_out: the whole-run view stored at the"),
        (_series("top_tension", lambda v: 0 * v), r"top_tension: the whole-run view stored at "),
        (
            _scene("numerics.duration", 24.0, "segment_0"),
            r"segment_1: its scene differs from segment_0's \(numerics\.duration: 24\.0 against",
        ),
    ],
)
def test_an_edited_line_run_file_is_refused(tmp_path, line_file, change, message):
    path = shutil.copy(line_file, tmp_path / "forged.nc")
    assert LineTrajectory.load(path).time[-1] == 12.0
    _edit(path, change)
    with pytest.raises(ValueError, match=r"forged\.nc: .*" + message):
        LineTrajectory.load(path)


def test_a_run_inside_another_result_is_checked_by_its_own_series(run_file):
    """check_figures, for a run kept in an OcpResult or an MpcResult: a plant that stopped
    early is genuine (its Omega is its own), an edited Omega is not."""
    from dataclasses import replace

    from cable_ocp.simulation.seabed import rms_objective
    from cable_ocp.simulation.trajectory import check_figures

    run = Trajectory.load(run_file)
    check_figures(run)
    cut = slice(0, 20)
    early = replace(
        run, time=run.time[cut], clearance_error=run.clearance_error[cut],
        omega=rms_objective(run.time[cut], run.clearance_error[cut]),
    )  # fmt: skip
    check_figures(early)
    with pytest.raises(ValueError, match=r"^omega = 0\.5 m: expected .* eq\. 39"):
        check_figures(replace(early, omega=0.5))
    with pytest.raises(ValueError, match=r"^time starts at 1 s: expected 0 s"):
        check_figures(replace(early, time=early.time + 1.0))


def test_a_run_whose_scene_file_this_machine_lacks_still_loads_and_is_checked(tmp_path):
    """A result folder moved away from its seabed grid: its scene cannot be rebuilt (the grid
    file is gone), but it loads, its numbers checked against the recorded scene."""
    grid = shutil.copy(MODELS / "data" / "survey_grid.nc", tmp_path / "grid.nc")
    scene = co.load_scene(
        MODELS / "survey.toml",
        {"seabed.grid.file": str(grid), "numerics.duration": 2.0, "model.elements": 5},
    )
    path = co.simulate(scene, quiet=True).save(tmp_path / "run")
    grid.unlink()
    assert Trajectory.load(path).time[-1] == 2.0
    _edit(path, _scene("numerics.duration", 4.0))
    with pytest.raises(ValueError, match=rf"run\.nc: .*time ends at 2 s: {DURATION} = 4\.0 s"):
        Trajectory.load(path)


def test_a_file_of_another_version_whose_scene_no_longer_validates_still_loads(tmp_path, run_file):
    """Old result files must load: the schema's rules may have changed since that version
    wrote the file, so its record is checked by its numbers as recorded. The same record in a
    file of this version is refused (a forged scene)."""
    path = shutil.copy(run_file, tmp_path / "old.nc")
    _edit(path, _scene("cable.density", "heavy"))
    with pytest.raises(ValueError, match=rf"old\.nc: .*{INVALID} \(cable\.density"):
        Trajectory.load(path)
    _edit(path, lambda d: d.setncattr("cable_ocp_version", "0.3.0"))
    assert Trajectory.load(path).time[-1] == 6.0
    _edit(path, _scene("numerics.duration", 12.0))
    with pytest.raises(ValueError, match=rf"old\.nc: .*time ends at 6 s: {DURATION} = 12\.0 s"):
        Trajectory.load(path)


def test_a_forged_omega_in_an_optimum_or_a_closed_loop_is_refused(tmp_path):
    """result.nc's Omega is its verified run's, and the run's own Omega is eq. 39's."""
    from cable_ocp.control.optimization import OcpResult
    from cable_ocp.result_files import netcdf

    optimum, run = _hanging_made_optimum()
    data = optimum.to_xarray()
    data["omega"] = data["omega"] + 0.5
    path = netcdf.write(data, tmp_path / "forged" / "result.nc")
    with pytest.raises(ValueError, match=r"omega = .*expected the verified run's Omega"):
        co.load_result(path)
    assert OcpResult.from_xarray(optimum.to_xarray()).omega == run.omega
    inner = optimum.to_xarray()
    inner["clearance_error"] = inner["clearance_error"] + 1.0
    with pytest.raises(ValueError, match=r"[Oo]mega"):
        OcpResult.from_xarray(inner)


def _hanging_made_optimum():
    """A made-up optimum around a 2 s hanging run (default elements, no solve), and the run."""
    run = co.simulate(co.load_scene("hanging").updated({"numerics.duration": 2.0}))
    return made_optimum(run), run


def _hanging_optimum(tmp_path):
    """A genuine result.nc of a 2 s hanging run on the default elements (no solve)."""
    optimum, run = _hanging_made_optimum()
    return optimum.save(tmp_path / "optimum"), run


def _records(key, value, names=("scene_record", "trajectory_scene_record")):
    """An edit of the scene records ``names`` (an optimum's and its verified run's) alike."""

    def edit(dataset):
        for name in names:
            record = json.loads(dataset.getncattr(name))
            section, _, field = key.partition(".")
            record[section][field] = value
            dataset.setncattr(name, json.dumps(record))

    return edit


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (_scene("model.elements", 7), r"scene_record: not the verified run's"),
        (_records("numerics.duration", 3.0), rf"time ends at 2 s: {DURATION} = 3\.0 s"),
        (_records("model.elements", 7), r"expected its scene's model\.elements = 7"),
    ],
)
def test_an_optimum_whose_scene_record_is_edited_is_refused(tmp_path, change, message):
    """Issue 45 (r5 J1): result.nc's scene_record is its verified run's, and that run is
    checked against its own record (its end, its elements), as a run's own file is."""
    folder, run = _hanging_optimum(tmp_path)
    path = folder / "result.nc" if folder.is_dir() else folder
    assert co.load_result(path).scene_record == run.scene_record
    _edit(path, change)
    with pytest.raises(ValueError, match=r"result\.nc: .*" + message):
        co.load_result(path)


def test_a_closed_loop_whose_plant_scene_is_edited_is_refused(tmp_path):
    """Issue 45 (r5 J2): mpc.nc's plant is checked against its own scene record: its elements
    always, its end where the loop claims it ran to the end (a success)."""
    from cable_ocp.control.closed_loop.result import MpcResult, SolveLog

    run = co.simulate(co.load_scene("hanging").updated({"numerics.duration": 2.0}))
    loop = MpcResult(
        trajectory=run, planned_angle=np.zeros(run.time.size),
        solves=SolveLog(np.zeros(1), np.full(1, 0.01), np.array([3]), ["Solve_Succeeded"]),
        failures=[], success=True, status="every solve succeeded", iterations=3,
        solve_time=0.01, worst_solve_time=0.01, limited_steps=0, projected_samples=0,
        angle_range=(-1.0, 1.0), real_time_factor=2.0, wall_time=0.5, build_time=0.2,
        settings={"horizon": 2.0},
    )  # fmt: skip
    path = loop.save(tmp_path / "loop")
    assert co.load_result(path).success
    elements = run.scene_record["model"]["elements"]
    forged = shutil.copy(path, tmp_path / "elements.nc")
    _edit(forged, _scene("model.elements", elements + 6))
    with pytest.raises(ValueError, match=rf"elements\.nc: .*model\.elements = {elements + 6}"):
        MpcResult.load(forged)
    longer = shutil.copy(path, tmp_path / "longer.nc")
    _edit(longer, _scene("numerics.duration", 4.0))
    with pytest.raises(ValueError, match=rf"longer\.nc: .*time ends at 2 s: {DURATION} = 4\.0 s"):
        MpcResult.load(longer)


@pytest.fixture(scope="module")
def landing_file(tmp_path_factory):
    """A LandingResult of test_lowering's landing scene run on the scene's own winch (no solve),
    its report and compensation ratio measured as co.land measures them."""
    from test_lowering import lowering_scene

    from cable_ocp.lowering.landing import LandingResult, _measured, landing_scene

    scene = landing_scene(lowering_scene())
    run = co.simulate(scene, quiet=True)
    optimum = made_optimum(run)
    report, ratio = _measured(scene, optimum)
    assert report is not None
    landing = LandingResult(scene, False, optimum, report, ratio, 1.0)
    return landing.save(tmp_path_factory.mktemp("landing") / "landing.nc")


def _root_scene(name):
    """An edit of a lowering result's root scene record: the bundled scene ``name``'s."""
    record = json.dumps(co.load_scene(name).to_dict())
    return lambda dataset: dataset.setncattr("scene_record", record)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (_in("report", _value("landing_error", 3.0)), r"report\.landing_error = 3\.0: its run"),
        (_in("report", _value("hold_deviation", 0.0)), r"report\.hold_deviation = 0\.0: its run"),
        (_in("report", _value("peak_tension", np.nan)), r"report\.peak_tension = nan: its run"),
        (_value("compensation_ratio", 99.0), r"compensation_ratio = 99\.0: its run gives nan"),
        (_root_scene("hanging"), r"scene_record: scene 'hanging' has no \[lowering\]"),
        (_scene("lowering.height", 9.0), r"scene_record: scene .* not the scene its result ran"),
    ],
)
def test_a_landing_whose_figures_its_run_does_not_give_is_refused(
    tmp_path, landing_file, change, message
):
    """Issue 45 (r5 J3): a saved landing's report is what its run gives, on its own scene."""
    assert co.load_result(landing_file).report is not None
    path = shutil.copy(landing_file, tmp_path / "forged.nc")
    _edit(path, change)
    with pytest.raises(ValueError, match=r"forged\.nc: not a readable landing .*" + message):
        co.load_result(path)


def test_a_landing_plan_whose_report_or_scene_is_forged_is_refused(tmp_path):
    """Issue 45 (r5 J3): a saved plan's report is what its verified run gives under the angle
    flown, its last landing error the report's, and its scene a [lowering] one, its run's."""
    from test_lowering import lowering_scene

    scene = lowering_scene(**{"numerics.duration": 200.0, "lowering.land_time": 170.0})
    genuine = co.plan_landing(scene).save(tmp_path / "plan.nc")
    assert co.load_result(genuine).run is not None
    for name, change, message in (
        ("error", _in("report", _value("landing_error", 3.0)), r"report\.landing_error = 3\.0"),
        ("errors", _series("landing_errors", lambda v: v + 1.0), r"landing_errors\[-1\] = "),
        ("check", _in("report", _halved_last_check), r"report\.checks\[\d+\]\.value = "),
        ("scene", _root_scene("hanging"), r"scene 'hanging' has no \[lowering\]"),
    ):
        path = shutil.copy(genuine, tmp_path / f"{name}.nc")
        _edit(path, change)
        with pytest.raises(
            ValueError, match=rf"{name}\.nc: not a readable landing plan .*{message}"
        ):
            co.load_result(path)


def _halved_last_check(group):
    """An edit of a report's table of checks (a JSON attribute): the last check's value halved."""
    checks = json.loads(group.getncattr("checks"))
    checks[-1]["value"] = 0.5 * checks[-1]["value"]
    group.setncattr("checks", json.dumps(checks))
