"""Writers of result format 1 (npz + json, cable_ocp 0.1), to test that such results still load.

Copies of the ``save`` methods of that version; the package itself writes netCDF only.
"""

from __future__ import annotations

import json
from dataclasses import asdict
from pathlib import Path

import numpy as np
import xarray as xr

from cable_ocp.scene.output import json_text

TRAJECTORY_ARRAYS = (
    "time", "states", "inputs", "joints", "tensions", "winch_angle", "clearance_error",
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
    if result.method != "nelder-mead":  # 0.1 kept the objective, Omega^2 (m^2)
        meta["history"] = [None if v is None else v**2 for v in meta["history"]]
    (folder / "result.json").write_text(json.dumps(meta, indent=1, allow_nan=False))
    np.savez(folder / "result.npz", parameters=result.parameters)


def _earlier_mpc(result) -> dict:
    """The fields of an MpcResult as formats 1 and 2 held them."""
    solves = result.solves
    return {
        "time": result.time, "winch_angle": result.trajectory.winch_angle,
        "planned_angle": result.planned_angle, "end": result.end, "top": result.top,
        "clearance_error": result.clearance_error, "sample_times": solves.sample_time,
        "solve_times": solves.solve_time, "iterations": solves.iterations,
    }  # fmt: skip


def write_mpc_result(result, folder: Path) -> None:
    """``mpc.json`` and ``mpc.npz`` as ``MpcResult.save`` of cable_ocp 0.1 wrote them."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    meta = {
        "omega_m": result.omega, "success": result.success, "status": result.status,
        "failures": result.failures, "real_time_factor": result.real_time_factor,
        "worst_solve_time_s": result.worst_solve_time, "wall_time_s": result.wall_time,
        "build_time_s": result.build_time, "limited_steps": result.limited_steps,
        "angle_range_rad": list(result.angle_range), "reference_omegas_m": {"locked": 0.2},
        "settings": result.settings, "statuses": result.solves.status,
    }  # fmt: skip
    (folder / "mpc.json").write_text(json.dumps(meta, indent=1))
    arrays = _earlier_mpc(result)
    arrays["reference locked"] = np.full(result.time.size, 0.2)
    np.savez_compressed(folder / "mpc.npz", **arrays)


def write_mpc_format_2(result, folder: Path) -> Path:
    """``mpc.nc`` as ``MpcResult.save`` of result format 2 wrote it (the run as end and top)."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    dims = {
        **{name: ("time",) for name in ("time", "winch_angle", "planned_angle",
                                        "clearance_error")},
        "end": ("time", "component"), "top": ("time", "component"),
        **{name: ("sample",) for name in ("sample_times", "solve_times", "iterations")},
        "angle_range": ("bound",),
    }  # fmt: skip
    variables = {name: (dims[name], value) for name, value in _earlier_mpc(result).items()}
    variables.update(
        omega=((), result.omega), success=((), result.success),
        limited_steps=((), result.limited_steps),
        angle_range=(("bound",), list(result.angle_range)),
        real_time_factor=((), result.real_time_factor),
        worst_solve_time=((), result.worst_solve_time), wall_time=((), result.wall_time),
        build_time=((), result.build_time), projected_samples=((), result.projected_samples),
    )  # fmt: skip
    attrs = {
        "cable_ocp_result": "MpcResult", "cable_ocp_format": 2, "cable_ocp_version": "0.1.0",
        "statuses": json.dumps(result.solves.status), "failures": json.dumps(result.failures),
        "settings": json.dumps(result.settings), "status": result.status,
    }  # fmt: skip
    data = xr.Dataset(variables, coords={"component": ["x", "y", "z"], "bound": ["min", "max"]},
                      attrs=attrs)  # fmt: skip
    data.to_netcdf(folder / "mpc.nc")
    return folder / "mpc.nc"
