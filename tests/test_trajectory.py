"""Trajectory files (cable_ocp.simulation.trajectory): a run saved and loaded back is the same run.

Truncated, garbled or ill-fitting files are refused with the file named.
"""

from __future__ import annotations

import json
import zipfile

import numpy as np
import pytest

from cable_ocp.scene.schema import load_scene
from cable_ocp.simulation.run import simulate
from cable_ocp.simulation.trajectory import Trajectory


def test_trajectory_round_trip(tmp_path, models_dir):
    run = simulate(load_scene(models_dir / "paper_flat.toml", {"numerics.duration": 10.0}))
    written = run.save(tmp_path / "run")
    assert [p.name for p in written] == ["run.npz", "run.json"]
    loaded = Trajectory.load(tmp_path / "run")
    assert loaded.equals(run)
    assert loaded.omega == run.omega and loaded.state_names == run.state_names
    np.testing.assert_array_equal(loaded.end, run.end)


def _trajectory(omega=0.25):
    k, n = 4, 2
    rng = np.random.default_rng(1)
    return Trajectory(
        time=np.linspace(0, 1, k),
        states=rng.normal(size=(k, 6)),
        inputs=rng.normal(size=(k, 15)),
        joints=rng.normal(size=(k, 3, n + 2)),
        tensions=rng.normal(size=(k, n + 1)),
        winch_angle=np.zeros(k),
        clearance_error=rng.normal(size=k),
        omega=omega,
        scene_name="test",
        state_names=[f"q{i}" for i in range(6)],
    )


@pytest.mark.parametrize("omega", [0.25, float("nan")])
def test_trajectory_round_trip_with_strict_json(tmp_path, omega):
    run = _trajectory(omega)
    run.save(tmp_path / "t")
    meta = (tmp_path / "t.json").read_text()
    assert "NaN" not in meta
    assert json.loads(meta)["omega"] == (None if np.isnan(omega) else omega)
    assert Trajectory.load(tmp_path / "t").equals(run)


def test_trajectory_load_names_a_truncated_or_garbled_file(tmp_path):
    _trajectory().save(tmp_path / "t")
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
    run.save(tmp_path / "t")
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
    with pytest.raises(ValueError, match=r"nothing\.npz: not a readable trajectory"):
        Trajectory.load(tmp_path / "nothing")
