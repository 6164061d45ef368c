"""Loaders of saved results check what they read (cable_ocp.scene.records).

``OcpResult.load`` and ``Trajectory.load`` refuse a file of result format 1 (json + npz) whose
fields have the wrong type or shape, or whose JSON is nested too deeply for Python, with one
``ValueError`` that names the file and the field; ``OcpResult.load``, ``Trajectory.load`` and
``MpcResult.load`` refuse a file of format 2 (netCDF) by the same checks. The results here are
built directly, and written as cable_ocp 0.1 did (tests/legacy_results.py) or by ``save``: no
solver runs.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
import xarray as xr
from legacy_results import write_mpc_format_2, write_mpc_result, write_ocp_result, write_trajectory

from cable_ocp.control.closed_loop.result import MpcResult, SolveLog
from cable_ocp.control.optimization import OcpResult
from cable_ocp.result_files import dataset as labelled
from cable_ocp.scene.records import check_field, control_parameters, record_fields
from cable_ocp.simulation.seabed import rms_objective
from cable_ocp.simulation.trajectory import Trajectory
from cable_ocp.simulation.trajectory_dataset import state_names

DEEP = "[" * 100_000 + "]" * 100_000


def _trajectory() -> Trajectory:
    k, n = 3, 2
    rng = np.random.default_rng(0)
    time = np.linspace(0, 1, k)
    states, inputs = rng.normal(size=(k, 2 * 5 * (n + 1))), rng.normal(size=(k, 15))
    joints, tensions = rng.normal(size=(k, 3, n + 2)), rng.normal(size=(k, n + 1))
    error = rng.normal(size=k)  # Omega is eq. 39 on it: Trajectory.load checks it
    return Trajectory(
        time=time, states=states, inputs=inputs, joints=joints, tensions=tensions,
        winch_angle=np.zeros(k), clearance_error=error, omega=rms_objective(time, error),
        scene_name="test",
        state_names=state_names(n + 1, 5),
    )  # fmt: skip


def _result(trajectory=None) -> OcpResult:
    return OcpResult(
        method="ipopt", parameters=np.linspace(0, 1, 84), control="hermite(84)",
        trajectory=trajectory, omega=trajectory.omega if trajectory else float("nan"),
        omega_model=0.02,
        success=True, status="Solve_Succeeded", iterations=12, evaluations=15, wall_time=3.0,
        build_time=1.0, solve_time=1.5, function_time=0.5, history=[1.0, float("nan")],
        refinements=[0.01],
    )  # fmt: skip


@pytest.fixture
def saved(tmp_path):
    """A result of format 1 in tmp_path/r (with its trajectory): the folder."""
    write_ocp_result(_result(_trajectory()), tmp_path / "r")
    return tmp_path / "r"


def test_a_result_loads_back(saved):
    back = OcpResult.load(saved)
    assert back.iterations == 12 and back.success is True and back.control == "hermite(84)"
    assert back.history[0] == 1.0 and np.isnan(back.history[1])
    np.testing.assert_array_equal(back.parameters, np.linspace(0, 1, 84))
    assert back.trajectory.equals(_trajectory())


@pytest.mark.parametrize(
    ("field", "value", "message"),
    [
        ("success", "yes", "success = 'yes': expected true or false"),
        ("success", 1, "success = 1: expected true or false"),
        ("iterations", 3.7, "iterations = 3.7: expected an integer >= 0"),
        ("iterations", float("inf"), "iterations = inf: expected an integer >= 0"),
        ("iterations", -1, "iterations = -1: expected an integer >= 0"),
        ("evaluations", True, "evaluations = True: expected an integer >= 0"),
        ("method", 5, "method = 5: expected a string"),
        ("method", "newton", "method = 'newton': must be one of 'shooting', 'nelder-mead'"),
        ("status", None, "status = None: expected a string"),
        ("omega", "0.1", "omega = '0.1': expected a finite number or null"),
        ("wall_time", float("nan"), "wall_time = nan: expected a finite number or null"),
        ("history", 1.0, "history = 1.0: expected a list of a finite number or nulls"),
        ("history", [1.0, "x"], "history[1] = 'x': expected a finite number or null"),
        ("control", "hermite", "control = 'hermite': expected a name and a size"),
        ("colour", "red", "unknown field(s) colour"),
        ("iterations", None, "iterations = None: expected an integer >= 0"),
    ],
)
def test_a_field_of_the_wrong_type_is_named(saved, field, value, message):
    path = saved / "result.json"
    meta = json.loads(path.read_text())
    meta[field] = value
    path.write_text(json.dumps(meta))  # Python's json writes inf and nan as Infinity, NaN
    with pytest.raises(ValueError) as error:
        OcpResult.load(saved)
    assert str(error.value).startswith(f"{path}: not a readable optimisation result")
    assert message in str(error.value)


def test_a_missing_field_is_named(saved):
    path = saved / "result.json"
    meta = json.loads(path.read_text())
    del meta["status"]
    path.write_text(json.dumps(meta))
    with pytest.raises(ValueError, match=r"result\.json: .*missing field\(s\) status"):
        OcpResult.load(saved)


@pytest.mark.parametrize("shape", [(2, 42), (3,), (85,), ()])
def test_parameters_of_the_wrong_shape_are_named(saved, shape):
    np.savez(saved / "result.npz", parameters=np.zeros(shape))
    with pytest.raises(ValueError) as error:
        OcpResult.load(saved)
    assert str(error.value).startswith(f"{saved / 'result.npz'}: not a readable optimisation")
    assert f"parameters of shape {shape}: control = 'hermite(84)' has 84 parameters" in str(
        error.value
    )


def test_parameters_that_are_not_finite_are_named(saved):
    np.savez(saved / "result.npz", parameters=np.full(84, np.nan))
    with pytest.raises(ValueError, match=r"result\.npz: .*parameters: not all finite"):
        OcpResult.load(saved)


@pytest.mark.parametrize("name", ["result.json", "trajectory.json"])
def test_json_nested_too_deeply_is_a_value_error_naming_the_file(saved, name):
    (saved / name).write_text(DEEP)
    with pytest.raises(ValueError) as error:
        OcpResult.load(saved)
    assert str(error.value).startswith(f"{saved / name}: not a readable")


def test_trajectory_json_nested_too_deeply_is_named(tmp_path):
    write_trajectory(_trajectory(), tmp_path / "t")
    (tmp_path / "t.json").write_text(DEEP)
    with pytest.raises(ValueError, match=r"t\.json: not a readable trajectory"):
        Trajectory.load(tmp_path / "t")


def test_record_fields_and_control_parameters_directly():
    types = {"name": str, "count": int, "value": float, "series": list[float]}
    meta = {"name": "a", "count": 2, "value": None, "series": [1, None]}
    fields = record_fields(meta, types)
    assert fields["count"] == 2 and np.isnan(fields["value"]) and np.isnan(fields["series"][1])
    assert record_fields({"name": "a"}, types, optional={"count", "value", "series"}) == {
        "name": "a"
    }
    with pytest.raises(ValueError, match="expected a JSON object of fields, got list"):
        record_fields([1, 2], types)
    assert control_parameters(np.zeros(14), "spline(14)").shape == (14,)
    with pytest.raises(ValueError, match="has 14 parameters"):
        control_parameters(np.zeros(13), "spline(14)")


def _rewrite(path, change) -> None:
    """Rewrite the netCDF file ``path`` with one field changed (a variable or an attribute).

    ``change`` is ``(name, value)``: a value None deletes the field; a tuple ``(dims, data)``
    replaces a variable's array.
    """
    name, value = change
    data = xr.load_dataset(path)
    if name in data.attrs:
        if value is None:
            del data.attrs[name]
        else:
            data.attrs[name] = value
    else:
        data = data.drop_vars(name)
        if value is not None:
            data[name] = value
    path.unlink()
    data.to_netcdf(path)


@pytest.fixture
def saved_nc(tmp_path):
    """A result of format 2 (result.nc, with its trajectory): the folder."""
    _result(_trajectory()).save(tmp_path / "r")
    return tmp_path / "r"


def test_a_result_of_format_2_loads_back(saved_nc):
    back = OcpResult.load(saved_nc)
    assert back.iterations == 12 and back.success is True and back.control == "hermite(84)"
    assert type(back.iterations) is int and type(back.omega) is float
    assert back.history[0] == 1.0 and np.isnan(back.history[1]) and back.refinements == [0.01]
    assert back.trajectory.equals(_trajectory())


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (("success", "yes"), "success = 'yes': expected true or false"),
        (("success", 1), "success = 1: expected true or false"),
        (("heave_feedforward", 0.0), "heave_feedforward = 0.0: expected true or false"),
        (("iterations", 3.7), "iterations = 3.7: expected an integer >= 0"),
        (("iterations", np.inf), "iterations = inf: expected an integer >= 0"),
        (("iterations", np.nan), "iterations = nan: expected an integer >= 0"),
        (("iterations", -1), "iterations = -1: expected an integer >= 0"),
        (("evaluations", True), "evaluations = True: expected an integer >= 0"),
        (("iterations", ("n", [1, 2])), "iterations = [1, 2]: expected an integer >= 0"),
        (("method", 5), "method = 5: expected a string"),
        (("method", "newton"), "method = 'newton': must be one of 'shooting', 'nelder-mead'"),
        (("status", 1.5), "status = 1.5: expected a string"),
        (("omega", "0.1"), "omega = '0.1': expected a finite number or NaN"),
        (("wall_time", np.inf), "wall_time = inf: expected a finite number or NaN"),
        (("omega_model", -np.inf), "omega_model = -inf: expected a finite number or NaN"),
        (("history", 1.0), "history = 1.0: expected a list of a finite number or nulls"),
        (("history", ("i", ["1.0", "x"])), "history[0] = '1.0': expected a finite number"),
        (("refinements", ("i", [0.1, np.inf])), "refinements[1] = inf: expected a finite"),
        (("control", "hermite"), "control = 'hermite': expected a name and a size"),
        (("parameters", ("p", ["a", "b"])), "parameters = an array of <U1 of shape (2,): expected"),
        (("parameters", ("p", np.full(84, np.nan))), "parameters: not all finite"),
        (("omega", ("t", [1.0, 2.0])), "omega = [1.0, 2.0]: expected a finite number or NaN"),
        (("trajectory_omega", "x"), "trajectory: omega = 'x': expected a finite number or NaN"),
        (("scene_name", 7), "trajectory: scene_name = 7: expected a string"),
        (("winch_angle", ("time", ["a", "b", "c"])), "trajectory: winch_angle = an array of <U1"),
        (("tension", (("time", "element"), np.full((3, 3), "x"))), "of shape (3, 3): expected an"),
        (("status", None), "missing field(s) status"),
        (("iterations", None), "missing field(s) iterations"),
        (("tension", None), "trajectory: missing field(s) tension"),
    ],
)
def test_a_result_of_format_2_with_a_field_of_the_wrong_type_is_named(saved_nc, change, message):
    """The netCDF result: the same fields, checked as strictly as format 1's, never coerced."""
    path = saved_nc / "result.nc"
    _rewrite(path, change)
    with pytest.raises(ValueError) as error:
        OcpResult.load(saved_nc)
    assert str(error.value).startswith(f"{path}: not a readable optimisation result")
    assert message in str(error.value) and "\n" not in str(error.value)


@pytest.mark.parametrize("shape", [(2, 42), (3,), (85,), ()])
def test_parameters_of_format_2_of_the_wrong_shape_are_named(saved_nc, shape):
    path = saved_nc / "result.nc"
    _rewrite(path, ("parameters", (("p", "q")[: len(shape)], np.zeros(shape))))
    with pytest.raises(ValueError) as error:
        OcpResult.load(saved_nc)
    assert str(error.value).startswith(f"{path}: not a readable optimisation result")
    assert f"parameters of shape {shape}: control = 'hermite(84)' has 84 parameters" in str(
        error.value
    )


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (("omega", "x"), "omega = 'x': expected a finite number or NaN"),
        (("scene_name", 7), "scene_name = 7: expected a string"),
        (("time", ("time", ["a", "b", "c"])), "time = an array of <U1 of shape (3,): expected"),
        (("scene_name", None), "missing field(s) scene_name"),
    ],
)
def test_a_trajectory_of_format_2_with_a_field_of_the_wrong_type_is_named(
    tmp_path, change, message
):
    path = _trajectory().save(tmp_path / "t")
    assert Trajectory.load(tmp_path / "t").equals(_trajectory())
    _rewrite(path, change)
    with pytest.raises(ValueError) as error:
        Trajectory.load(tmp_path / "t")
    assert str(error.value).startswith(f"{path}: not a readable trajectory")
    assert message in str(error.value)


def _mpc() -> MpcResult:
    k, s = 3, 2
    return MpcResult(
        trajectory=_trajectory(), planned_angle=np.zeros(k),
        solves=SolveLog(np.arange(s, dtype=float), np.full(s, 0.01), np.array([3, 4]),
                        ["Solve_Succeeded"] * s),
        failures=[], success=True, status="every solve succeeded", iterations=7,
        solve_time=0.02, worst_solve_time=0.01, limited_steps=0, projected_samples=0,
        angle_range=(-1.0, 1.0), real_time_factor=2.0, wall_time=0.5, build_time=0.2,
        settings={"horizon_s": 2.0},
    )  # fmt: skip


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (("success", "yes"), "success = 'yes': expected true or false"),
        (("limited_steps", 2.5), "limited_steps = 2.5: expected an integer >= 0"),
        (("angle_range", ("bound", [-1.0, np.inf])), "angle_range[1] = inf: expected a finite"),
        (("angle_range", ("b", [1.0, 2.0, 3.0])), "angle_range = [1.0, 2.0, 3.0]: expected 2"),
        (("solves_status", '["ok", 3]'), "status[1] = 3: expected a string"),
        (("solves_status", "[1"), "status: Expecting"),
        (("settings", "[" * 100_000 + "]" * 100_000), "settings: JSON nested too deeply"),
        (("settings", "[1, 2]"), "settings = [1, 2]: expected a mapping of names"),
        (("solves_iterations", ("solve", ["a", "b"])), "iterations = an array of <U1 of shape"),
        (("omega", None), "trajectory: missing field(s) omega"),
    ],
)
def test_an_mpc_result_with_a_field_of_the_wrong_type_is_named(tmp_path, change, message):
    path = _mpc().save(tmp_path / "m")
    assert labelled.fields_equal(MpcResult.load(tmp_path / "m"), _mpc())
    _rewrite(path, change)
    with pytest.raises(ValueError) as error:
        MpcResult.load(tmp_path / "m")
    assert str(error.value).startswith(f"{path}: not a readable closed-loop result")
    assert message in str(error.value)


def test_an_mpc_result_of_format_1_and_2_loads(tmp_path):
    """Files of cable_ocp 0.1 (mpc.json + mpc.npz) and of format 2 (the run as its end and top
    over time): the run, its solves and its figures as they were; the reference runs left out."""
    new = _mpc()
    for write, folder in ((write_mpc_result, tmp_path / "1"), (write_mpc_format_2, tmp_path / "2")):
        write(new, folder)
        old = MpcResult.load(folder)
        np.testing.assert_array_equal(old.end, new.end)
        np.testing.assert_array_equal(old.top, new.top)
        np.testing.assert_array_equal(old.time, new.time)
        np.testing.assert_array_equal(old.clearance_error, new.clearance_error)
        assert old.omega == new.omega and old.iterations == 7 and old.solve_time == 0.02
        assert labelled.fields_equal(old.solves, new.solves)
        assert old.summary()["omega"] == new.omega and old.success


def test_check_field_directly():
    assert check_field("a", np.int64(3), int) == 3 and check_field("s", ["x"], list[str]) == ["x"]
    assert check_field("t", [1, 2.5], tuple[float, float]) == (1.0, 2.5)
    assert check_field("t", [1, None, 2], tuple[float, ...])[:1] == (1.0,)
    assert np.isnan(check_field("v", float("nan"), float, nan=True))
    with pytest.raises(ValueError, match="v = nan: expected a finite number or null"):
        check_field("v", float("nan"), float)
    with pytest.raises(ValueError, match=r"d\['k'\] = 'x': expected a finite number"):
        check_field("d", {"k": "x"}, dict[str, float])
    with pytest.raises(ValueError, match="a = 'x': expected an array of numbers"):
        check_field("a", "x", np.ndarray)
