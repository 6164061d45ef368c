"""``load_result(path)``: any result folder or file that cable_ocp wrote, read by what it holds."""

from __future__ import annotations

from pathlib import Path

from cable_ocp.control.closed_loop.result import MPC_FILE, MpcResult
from cable_ocp.control.optimization import RESULT_FILE, OcpResult
from cable_ocp.simulation.trajectory import Trajectory

TRAJECTORY_FILE = "trajectory.nc"


def load_result(path: str | Path) -> OcpResult | MpcResult | Trajectory:
    """Read what ``optimize``, ``mpc`` or ``simulate`` saved (the API's or the command line's).

    Parameters
    ----------
    path : path-like
        A results folder (holding ``result.nc``, ``mpc.nc`` or ``trajectory.nc``, looked for in
        that order), or one of those files.

    Returns
    -------
    OcpResult, MpcResult or Trajectory
        Each holds the scene it ran (``.scene``), so ``simulate(result.scene, winch=result)``
        replays an optimum.

    Raises
    ------
    ValueError
        Naming the path, when it holds none of them, or the file that cannot be read.
    """
    path = Path(path)
    folder, name = (path.parent, path.name) if path.suffix == ".nc" else (path, None)
    readers = {
        RESULT_FILE: OcpResult.load,
        MPC_FILE: MpcResult.load,
        TRAJECTORY_FILE: lambda where: Trajectory.load(where / "trajectory"),
    }
    for file, read in readers.items():
        if (name is None and (folder / file).is_file()) or name == file:
            return read(folder)
    raise ValueError(
        f"{path}: no cable_ocp result there (expected a folder or file of {', '.join(readers)})"
    )
