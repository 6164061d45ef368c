"""Loaders refuse hostile or inconsistent result files before reading their data.

One ``ValueError`` naming the file and the field: a file declaring more data than it can hold, a
series over another dimension than time, a format that is not a known positive integer, a boolean
that is not 0 or 1, a run whose time does not increase or whose positions are not finite.
"""

from __future__ import annotations

import netCDF4
import numpy as np
import pytest
from test_records import _mpc, _result, _trajectory

from cable_ocp.control.closed_loop.result import MpcResult
from cable_ocp.control.optimization import OcpResult
from cable_ocp.simulation.trajectory import Trajectory


def _edit(path, change) -> None:
    """Apply ``change(dataset)`` to the netCDF file in place (netCDF4, no rewrite by xarray)."""
    with netCDF4.Dataset(path, "a") as dataset:
        change(dataset)


def test_a_file_declaring_more_data_than_it_holds_is_refused_unread(tmp_path):
    path = _trajectory().save(tmp_path / "t")

    def huge(dataset):
        dataset.createDimension("sample", 2_000_000_000)
        dataset.createVariable("extra", "f8", ("sample",), chunksizes=(1024,))

    _edit(path, huge)
    with pytest.raises(ValueError, match=r"t\.nc: declares more data than its \d+ bytes .*extra"):
        Trajectory.load(tmp_path / "t")


def test_a_series_over_another_dimension_than_time_is_refused(tmp_path):
    path = _mpc().save(tmp_path / "m")

    def elsewhere(dataset):
        dataset.createDimension("other", 7)
        variable = dataset.createVariable("planned", "f8", ("other",))
        variable[:] = np.zeros(7)
        dataset.renameVariable("planned_angle", "planned_old")
        dataset.renameVariable("planned", "planned_angle")

    _edit(path, elsewhere)
    with pytest.raises(ValueError, match=r"mpc\.nc: .*planned_angle of shape \(7,\) does not fit"):
        MpcResult.load(tmp_path / "m")


@pytest.mark.parametrize(
    ("version", "message"),
    [
        (0, "not a format of netCDF results"),
        (1, "not a format of netCDF results"),
        (np.float64(2.0), "expected an integer"),
        ("3", "expected an integer"),
    ],
)
def test_a_format_that_is_not_a_known_positive_integer_is_refused(tmp_path, version, message):
    path = _mpc().save(tmp_path / "m")
    _edit(path, lambda dataset: dataset.setncattr("cable_ocp_format", version))
    with pytest.raises(ValueError, match=rf"mpc\.nc: cable_ocp_format = .*{message}"):
        MpcResult.load(tmp_path / "m")


def test_a_boolean_that_is_not_0_or_1_is_refused(tmp_path):
    folder = tmp_path / "r"
    path = _result().save(folder)

    def two(dataset):
        dataset["heave_feedforward"].assignValue(2)

    _edit(path, two)
    with pytest.raises(ValueError, match=r"result\.nc: heave_feedforward = 2: expected true or"):
        OcpResult.load(folder)


@pytest.mark.parametrize(
    ("name", "value", "message"),
    [
        ("time", lambda t: np.r_[t[:2], t[1], t[3:]], "time: not strictly increasing"),
        ("joint_position", lambda p: np.where(p == p.max(), np.inf, p), "joints: not all finite"),
    ],
)
def test_a_run_whose_time_repeats_or_whose_joints_are_infinite_is_refused(
    tmp_path, name, value, message
):
    path = _trajectory().save(tmp_path / "t")

    def spoil(dataset):
        dataset[name][:] = value(dataset[name][:].filled())

    _edit(path, spoil)
    with pytest.raises(ValueError, match=rf"t\.nc: not a readable trajectory .*{message}"):
        Trajectory.load(tmp_path / "t")


def test_a_trajectory_variable_over_other_dimensions_is_named(tmp_path):
    data = _trajectory().to_xarray()
    data["top_position"] = (("time", "axis"), np.zeros((data.sizes["time"], 4)))
    data.to_netcdf(tmp_path / "t.nc")
    with pytest.raises(ValueError, match=r"t\.nc: not a readable trajectory .*top_position over"):
        Trajectory.load(tmp_path / "t")


# --- a line run's file: its groups against the file's size, its root and its scene (issue 45) ---


def _scene_edit(dataset) -> None:
    import json

    group = dataset["segment_1"]
    record = json.loads(group.getncattr("scene_record"))
    record["cable"]["diameter"] *= 2
    group.setncattr("scene_record", json.dumps(record))


def _huge_group(dataset) -> None:
    group = dataset["segment_1"]
    group.createDimension("sample", 20_000_000)
    group.createVariable("extra", "f8", ("sample", "element"), chunksizes=(1024, 1))


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (_huge_group, r"declares more data than its \d+ bytes can hold \(segment_1/extra over"),
        (lambda d: d.setncattr("segments", -1), r"segments = -1: expected the number of its "),
        (lambda d: d.setncattr("segments", 5), r"segments = 5: .* \(2, at least 1\)"),
        (lambda d: d.setncattr("element_length", 5.0),
         r"element_length = 5 m: its scene's winch.line.element_length is 10 m"),
        (lambda d: d.setncattr("element_length", np.nan), r"element_length = nan: expected a "),
        (_scene_edit, r"segment_1: its scene differs from segment_0's \(cable.diameter: "),
    ],
)  # fmt: skip
def test_a_line_runs_groups_are_checked_against_the_file_and_the_scene(
    tmp_path, line_file, change, message
):
    """A landing.nc or a pay-out's trajectory.nc: every group, not the root alone (a segment's
    2e8 x 4 x 3 values raised a MemoryError); its attributes against its groups and its scene
    (element_length = 5 made check_landing report 270.9 kN instead of 27.2 kN)."""
    import shutil

    from cable_ocp.simulation.line_trajectory import LineTrajectory

    path = shutil.copy(line_file, tmp_path / "landing.nc")
    _edit(path, change)
    with pytest.raises(ValueError, match=r"landing\.nc: (.*landing\.nc: )?" + message):
        LineTrajectory.load(path)
