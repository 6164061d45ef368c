"""Writers of result format 1 (npz + json, cable_ocp 0.1), to test that such results still load.

Copies of the ``save`` methods of that version; the package itself writes netCDF only.
"""

from __future__ import annotations

import json
from dataclasses import asdict
from pathlib import Path

import numpy as np

from cable_ocp.scene.output import json_text

TRAJECTORY_ARRAYS = (
    "time", "states", "inputs", "joints", "tensions", "winch_angle", "clearance_error",
)  # fmt: skip
MPC_ARRAYS = (
    "time", "winch_angle", "planned_angle", "end", "top", "clearance_error",
    "sample_times", "solve_times", "iterations",
)  # fmt: skip


def write_trajectory(run, path: Path) -> tuple[Path, Path]:
    """``path.npz`` and ``path.json`` as ``Trajectory.save`` of cable_ocp 0.1 wrote them."""
    path = Path(path)
    arrays, meta = path.with_suffix(".npz"), path.with_suffix(".json")
    np.savez_compressed(arrays, **{name: getattr(run, name) for name in TRAJECTORY_ARRAYS})
    meta.write_text(json_text({"omega": run.omega, "scene_name": run.scene_name,
                               "state_names": run.state_names}))  # fmt: skip
    return arrays, meta


def _json_value(value):
    if isinstance(value, list):
        return [_json_value(v) for v in value]
    if isinstance(value, float) and not np.isfinite(value):
        return None
    return value


def write_ocp_result(result, folder: Path) -> None:
    """``result.json``, ``result.npz`` and the trajectory, as ``OcpResult.save`` of 0.1 wrote."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    if result.trajectory is not None:
        write_trajectory(result.trajectory, folder / "trajectory")
    meta = {
        k: _json_value(v)
        for k, v in asdict(result).items()
        if k not in ("parameters", "trajectory", "scene_record")
    }  # fmt: skip (not in 0.1)
    (folder / "result.json").write_text(json.dumps(meta, indent=1, allow_nan=False))
    np.savez(folder / "result.npz", parameters=result.parameters)


def write_mpc_result(result, folder: Path) -> None:
    """``mpc.json`` and ``mpc.npz`` as ``MpcResult.save`` of cable_ocp 0.1 wrote them."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    meta = {**result.summary(), "statuses": result.statuses}
    (folder / "mpc.json").write_text(json.dumps(meta, indent=1))
    arrays = {name: getattr(result, name) for name in MPC_ARRAYS}
    arrays.update({f"reference {k}": v for k, v in result.references.items()})
    np.savez_compressed(folder / "mpc.npz", **arrays)
