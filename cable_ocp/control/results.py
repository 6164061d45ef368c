"""A result folder or file read by the kind it declares: the mechanism, and this layer's kinds.

:func:`read_result` finds a folder's result file and reads it by its kind with the readers it
is given; :data:`READERS` are the kinds of this layer and those below it (an optimum, a closed
loop, a run). :func:`cable_ocp.lowering.results.load_result` (``co.load_result``) reads with
them and the lowering's kinds, which this layer cannot import.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping
from pathlib import Path

from cable_ocp import result_files
from cable_ocp.control.closed_loop import result as mpc_result
from cable_ocp.control.closed_loop.result import MPC_FILE, MpcResult
from cable_ocp.control.optimization import RESULT_FILE, WHAT, OcpResult
from cable_ocp.result_files import netcdf
from cable_ocp.simulation.line_trajectory import LineTrajectory
from cable_ocp.simulation.trajectory import Trajectory

TRAJECTORY_FILE = "trajectory.nc"
LANDING_FILE = "landing.nc"  # cable-ocp lower's open-loop landing run
# The files a results folder holds its result in, looked for in this order.
FOLDER_FILES = (RESULT_FILE, MPC_FILE, TRAJECTORY_FILE, LANDING_FILE)
# The reader of each kind of result file (its global attribute cable_ocp_result).
READERS = {
    "OcpResult": lambda path: result_files.load(OcpResult, path, WHAT),
    "MpcResult": lambda path: result_files.load(MpcResult, path, mpc_result.WHAT),
    "Trajectory": Trajectory.load,
    "LineTrajectory": LineTrajectory.load,
}

Result = OcpResult | MpcResult | Trajectory | LineTrajectory


def read_result(path: str | Path, readers: Mapping[str, Callable[[Path], object]]):
    """Read a result folder or file by the kind it declares, with the reader of that kind.

    Parameters
    ----------
    path : path-like
        A results folder (holding ``result.nc``, ``mpc.nc``, ``trajectory.nc`` or
        ``landing.nc``, looked for in that order; an optimum or closed loop of cable_ocp 0.1's
        ``result.json`` or ``mpc.json``), or any result file, whatever its name (``cable-ocp
        lower``'s ``hover_optimised.nc``, ``hover_closed_loop.nc``, ``hold.nc``): its kind is
        read from the file.
    readers : mapping of str to callable
        The reader of each kind (the file's global attribute ``cable_ocp_result``).

    Returns
    -------
    The result
        Each holds the scene it ran (``.scene``), so ``simulate(result.scene, winch=result)``
        replays an optimum.

    Raises
    ------
    TypeError
        ``path`` is not a path (a number, None).
    ValueError
        Naming the path, when it holds none of them, or the file that cannot be read.
    """
    if not isinstance(path, str | os.PathLike):
        raise TypeError(
            f"load_result: path must be a result folder's or file's path (str or Path); got "
            f"{type(path).__name__}"
        )
    path = Path(path)
    if not path.exists() and not path.suffix and path.with_suffix(".nc").is_file():
        path = path.with_suffix(".nc")  # as Trajectory.save was given it: run/trajectory
    if not path.exists():
        raise ValueError(f"{path}: no such file or folder")
    if path.is_dir():
        found = [name for name in FOLDER_FILES if (path / name).is_file()]
        if not found and (path / "result.json").is_file():
            return OcpResult.load(path)
        if not found and (path / "mpc.json").is_file():
            return MpcResult.load(path)
        if not found and (path / result_files.SWEEP_FILE).is_file():
            return result_files.read_sweep(path / result_files.SWEEP_FILE)
        if not found:
            raise ValueError(
                f"{path}: no cable_ocp result there (expected a folder holding one of "
                f"{', '.join(FOLDER_FILES)}, or a result file)"
            )
        path = path / found[0]
    if path.name == result_files.SWEEP_FILE:  # a sweep's, of any version
        return result_files.read_sweep(path)
    kind = netcdf.kind_of(path)
    if kind not in readers:
        raise ValueError(
            f"{path}: holds a {kind}, which load_result does not read (it reads "
            f"{', '.join(readers)})"
        )
    return readers[kind](path)
