"""Trajectory files (cable_ocp.trajectory): a run saved and loaded back is the same run."""

from __future__ import annotations

import numpy as np

from cable_ocp.scene import load_scene
from cable_ocp.simulation import simulate
from cable_ocp.trajectory import Trajectory


def test_trajectory_round_trip(tmp_path, models_dir):
    run = simulate(load_scene(models_dir / "paper_flat.toml", {"numerics.duration": 10.0}))
    written = run.save(tmp_path / "run")
    assert [p.name for p in written] == ["run.npz", "run.json"]
    loaded = Trajectory.load(tmp_path / "run")
    assert loaded.equals(run)
    assert loaded.omega == run.omega and loaded.state_names == run.state_names
    np.testing.assert_array_equal(loaded.end, run.end)
