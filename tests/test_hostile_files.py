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
