"""One case of a sweep, run where Dask puts it: a plain dict of arrays and scalars back.

Nothing escapes :func:`run_case`: an exception becomes a failed record with its reason, so one
bad case never stops a sweep.
"""

from __future__ import annotations

import time
import traceback
from typing import Any

import numpy as np

from cable_ocp.scene.schema import Scene

# The time series each case returns (all on the case's output times, s).
SERIES = ("winch_angle", "end_x", "end_y", "end_z", "clearance_error", "top_tension")


def _series(trajectory) -> dict[str, np.ndarray]:
    end = trajectory.end
    return {
        "time": np.asarray(trajectory.time, dtype=float),
        "winch_angle": np.asarray(trajectory.winch_angle, dtype=float),
        "end_x": end[:, 0].astype(float),
        "end_y": end[:, 1].astype(float),
        "end_z": end[:, 2].astype(float),
        "clearance_error": np.asarray(trajectory.clearance_error, dtype=float),
        "top_tension": np.asarray(trajectory.top_tension, dtype=float),
    }


def _reason(error: BaseException) -> str:
    """``Type: message (file:line)`` of the innermost frame, for the record."""
    frames = traceback.extract_tb(error.__traceback__)
    where = f" ({frames[-1].filename.rsplit('/', 1)[-1]}:{frames[-1].lineno})" if frames else ""
    return f"{type(error).__name__}: {error}{where}"


def run_case(scene: Scene, task: str, method: str, settings: Any) -> dict[str, Any]:
    """Simulate or optimise one scene; never raises.

    Parameters
    ----------
    scene : Scene
    task : str
        ``"simulate"`` (locked winch) or ``"optimize"``.
    method : str
        ``"shooting"`` or ``"nelder-mead"`` (optimize).
    settings : OcpSettings or None
        The optimiser's settings (``SweepSpec.settings``; None: optimize()'s defaults).

    Returns
    -------
    dict
        ``success`` (bool), ``status`` (``"ok"`` or ``"failed"``), ``reason`` (empty when ok),
        ``omega`` (m, NaN without a trajectory), ``wall_time`` (s), the time series of
        :data:`SERIES` with ``time`` (absent without a trajectory) and, for optimize,
        ``omega_model`` (m), ``iterations``, ``evaluations`` and ``solver_status``.
    """
    from cable_ocp.control.optimization import optimize
    from cable_ocp.control.solvers import solver_for
    from cable_ocp.simulation.run import simulate

    started = time.perf_counter()
    record: dict[str, Any] = {"success": False, "status": "failed", "reason": ""}
    try:
        if task == "simulate":
            trajectory = simulate(scene, quiet=True)
            record.update(success=True, status="ok")
        else:
            solver = solver_for(method, None) if settings is None else None
            result = optimize(scene, solver, settings, quiet=True)
            trajectory = result.trajectory
            record.update(
                success=bool(result.success),
                status="ok" if result.success else "failed",
                reason="" if result.success else f"{method}: {result.status}",
                omega_model=float(result.omega_model),
                iterations=int(result.iterations),
                evaluations=int(result.evaluations),
                solver_status=str(result.status),
            )
    except Exception as error:  # a failed case is data, not a crash of the sweep
        trajectory = None
        record["reason"] = _reason(error)
    record["omega"] = float(trajectory.omega) if trajectory is not None else float("nan")
    if trajectory is not None:
        record.update(_series(trajectory))
    record["wall_time"] = time.perf_counter() - started
    return record
