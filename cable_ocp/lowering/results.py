"""``load_result(path)`` (``co.load_result``): any result cable_ocp wrote, read by what it holds.

The control layer's kinds (:data:`cable_ocp.control.results.READERS`: an optimum, a closed loop,
a run) and the lowering's: an open-loop landing (:class:`~.plan.LandingPlan`), a landing from
the hover (:class:`~.landing.LandingResult`) and a hold (:class:`~.hold.HoldResult`).
"""

from __future__ import annotations

from pathlib import Path

from cable_ocp.control import results
from cable_ocp.lowering.hold import HoldResult
from cable_ocp.lowering.landing import LandingResult
from cable_ocp.lowering.plan import LandingPlan

# The reader of each kind of result file (its global attribute cable_ocp_result).
READERS = {
    **results.READERS,
    **{cls.__name__: cls.load for cls in (LandingPlan, LandingResult, HoldResult)},
}

Result = results.Result | LandingPlan | LandingResult | HoldResult


def load_result(path: str | Path) -> Result:
    """Read any result that cable_ocp saved (:func:`~cable_ocp.control.results.read_result`).

    What ``optimize``, ``mpc``, ``simulate``, ``plan_landing``, ``land``, ``hold`` or
    ``cable-ocp lower`` saved.

    Parameters
    ----------
    path : path-like
        A results folder (holding ``result.nc``, ``mpc.nc``, ``trajectory.nc`` or
        ``landing.nc``, looked for in that order; cable_ocp 0.1's ``result.json`` or
        ``mpc.json``), or any result file, whatever its name: its kind is read from the file.

    Returns
    -------
    OcpResult, MpcResult, Trajectory, LineTrajectory, LandingPlan, LandingResult or HoldResult
        A run of a line paid out by elements (``[winch.line]``) is a LineTrajectory. Each holds
        the scene it ran (``.scene``), so ``simulate(result.scene, winch=result)`` replays an
        optimum.

    Raises
    ------
    TypeError
        ``path`` is not a path.
    ValueError
        Naming the path, when it holds no result, or the file that cannot be read.
    """
    return results.read_result(path, READERS)
