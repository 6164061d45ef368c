"""Trajectory files (cable_ocp.simulation.trajectory): a run saved and loaded back is the same run.

netCDF (result format 2) with units on every variable; files of format 1 (npz + json) still
load. Truncated, garbled or ill-fitting files are refused with the file named.
"""

from __future__ import annotations

import json
import zipfile
from dataclasses import replace

import numpy as np
import pytest
import xarray as xr
from legacy_results import write_trajectory

from cable_ocp.result_files.netcdf import FORMAT
from cable_ocp.scene.schema import load_scene
from cable_ocp.simulation.run import simulate
from cable_ocp.simulation.seabed import rms_objective
from cable_ocp.simulation.trajectory import Trajectory
from cable_ocp.simulation.trajectory_dataset import state_names


@pytest.fixture(scope="module")
def flat_run(models_dir):
    return simulate(load_scene(models_dir / "paper_flat.toml", {"numerics.duration": 10.0}))


def test_trajectory_round_trip(tmp_path, flat_run):
    run = flat_run
    written = run.save(tmp_path / "run")
    assert written == tmp_path / "run.nc" and [p.name for p in tmp_path.iterdir()] == ["run.nc"]
    loaded = Trajectory.load(tmp_path / "run")
    assert loaded.equals(run)
    assert loaded.omega == run.omega and loaded.state_names == run.state_names
    np.testing.assert_array_equal(loaded.end, run.end)
    assert Trajectory.load(written).equals(run)  # the file's own name works too


def test_trajectory_file_has_units_on_every_variable(tmp_path, flat_run):
    """What a user of open_dataset sees: named dimensions, coordinates, CF units, long names."""
    with xr.open_dataset(flat_run.save(tmp_path / "run")) as data:
        assert set(data.dims) == {"time", "element", "joint", "component", "angle"}
        for name, variable in data.variables.items():
            assert variable.attrs.get("units"), name
            assert variable.attrs.get("long_name"), name
        assert data["time"].attrs["units"] == "s" and data["tension"].attrs["units"] == "N"
        assert data["velocity"].attrs["units"] == "m s-1"
        assert list(data["component"].values) == ["x", "y", "z"]
        assert data.sizes["joint"] == data.sizes["element"] + 1 == 17
        # The end E is joint 0; its position is element 0's lower end, A_0.
        end = data["joint_position"].sel(joint=0)
        np.testing.assert_array_equal(end.values, flat_run.end)
        np.testing.assert_array_equal(data["position"].sel(element=0).values, flat_run.end)
        assert data.attrs["scene_name"] == "paper_flat" and data.attrs["cable_ocp_format"] == FORMAT


def test_a_trajectory_of_format_1_still_loads(tmp_path, flat_run):
    write_trajectory(flat_run, tmp_path / "old")
    # Format 1 kept no scene, signed tensions or bond residual: the rest is the run as it was.
    assert Trajectory.load(tmp_path / "old").equals(
        replace(
            flat_run, scene_record={}, signed_tensions=np.zeros((0, 0)), bond_residual=float("nan")
        )
    )


def test_a_newer_or_foreign_file_is_named_with_its_version(tmp_path):
    run = _trajectory()
    data = run.to_xarray()
    data.attrs["cable_ocp_format"] = FORMAT + 1
    data.to_netcdf(tmp_path / "new.nc")
    with pytest.raises(ValueError, match=rf"new\.nc: written in result format {FORMAT + 1} by"):
        Trajectory.load(tmp_path / "new")
    xr.Dataset({"a": ("t", [1.0])}).to_netcdf(tmp_path / "other.nc")
    with pytest.raises(ValueError, match=r"other\.nc: not a cable_ocp result"):
        Trajectory.load(tmp_path / "other.nc")
    (tmp_path / "bad.nc").write_bytes(b"not netCDF at all")
    with pytest.raises(ValueError, match=r"bad\.nc: not a readable netCDF file"):
        Trajectory.load(tmp_path / "bad")


def _trajectory(k=4):
    """A run of ``k`` random samples, its Omega that of its e(t) (NaN for a single sample)."""
    n = 2
    rng = np.random.default_rng(1)
    time, error = np.linspace(0, 1, k), rng.normal(size=k)
    return Trajectory(
        time=time,
        states=rng.normal(size=(k, 2 * 5 * (n + 1))),
        inputs=rng.normal(size=(k, 15)),
        joints=rng.normal(size=(k, 3, n + 2)),
        tensions=rng.normal(size=(k, n + 1)),
        winch_angle=np.zeros(k),
        clearance_error=error,
        omega=rms_objective(time, error) if k > 1 else float("nan"),
        scene_name="test",
        state_names=state_names(n + 1, 5),
    )


@pytest.mark.parametrize("samples", [4, 1])
def test_trajectory_round_trip_with_nan(tmp_path, samples):
    run = _trajectory(samples)
    run.save(tmp_path / "t")
    assert Trajectory.load(tmp_path / "t").equals(run)


@pytest.mark.parametrize("samples", [4, 1])
def test_format_1_round_trip_with_strict_json(tmp_path, samples):
    run = _trajectory(samples)
    write_trajectory(run, tmp_path / "t")
    meta = (tmp_path / "t.json").read_text()
    assert "NaN" not in meta
    assert json.loads(meta)["omega"] == (None if np.isnan(run.omega) else run.omega)
    assert Trajectory.load(tmp_path / "t").equals(run)


def test_trajectory_load_names_a_truncated_or_garbled_file(tmp_path):
    _trajectory().save(tmp_path / "t")
    netcdf = tmp_path / "t.nc"
    data = netcdf.read_bytes()
    for size in (0, 10, len(data) // 2):
        netcdf.write_bytes(data[:size])
        with pytest.raises(ValueError, match=r"t\.nc: not a readable"):
            Trajectory.load(tmp_path / "t")


def test_format_1_load_names_a_truncated_or_garbled_file(tmp_path):
    write_trajectory(_trajectory(), tmp_path / "t")
    npz, meta = tmp_path / "t.npz", tmp_path / "t.json"
    data, text = npz.read_bytes(), meta.read_text()
    for size in (0, 10, len(data) // 2, len(data) - 30):
        npz.write_bytes(data[:size])
        with pytest.raises(ValueError, match=r"t\.npz: not a readable trajectory"):
            Trajectory.load(tmp_path / "t")
    npz.write_bytes(data)
    garbled = [text[: len(text) // 2], "[]", text.replace('"omega"', '"omgea"')]
    garbled += [text.replace('"test"', "3"), b"\xff\xfe"]
    for bad in garbled:
        if isinstance(bad, bytes):
            meta.write_bytes(bad)
        else:
            meta.write_text(bad)
        with pytest.raises(ValueError, match=r"t\.json: not a readable trajectory"):
            Trajectory.load(tmp_path / "t")


def test_trajectory_load_rejects_arrays_that_do_not_fit(tmp_path):
    run = _trajectory()
    write_trajectory(run, tmp_path / "t")
    arrays = {name: getattr(run, name) for name in ("time", "states", "inputs", "joints")}
    arrays |= {"tensions": run.tensions[:, :2], "winch_angle": run.winch_angle,
               "clearance_error": run.clearance_error}  # fmt: skip
    np.savez(tmp_path / "t.npz", **arrays)
    with pytest.raises(ValueError, match=r"t\.npz: .*joints of shape \(4, 3, 4\) do not fit"):
        Trajectory.load(tmp_path / "t")
    np.savez(tmp_path / "t.npz", time=run.time)
    with pytest.raises(ValueError, match=r"t\.npz: not a readable trajectory \(KeyError"):
        Trajectory.load(tmp_path / "t")
    with zipfile.ZipFile(tmp_path / "t.npz", "w") as z:
        z.writestr("time.npy", b"not an array")
    with pytest.raises(ValueError, match=r"t\.npz: not a readable trajectory"):
        Trajectory.load(tmp_path / "t")


def test_trajectory_load_of_a_missing_file_names_it(tmp_path):
    with pytest.raises(ValueError, match=r"nothing\.nc: no such file"):
        Trajectory.load(tmp_path / "nothing")
