"""The drum's range after a run: the winch angle within ``[winch.angle_min, winch.angle_max]``.

``winch.angle_min`` and ``winch.angle_max`` bound the angle the drum can turn to (for a line on
the drum, ``-haul_in_max / r_D`` and ``pay_out_max / r_D``). A run driven beyond them (a
profile written by hand, an optimum replayed on a narrower winch) shows a drum the scene does
not have: it fails its physics check (:mod:`cable_ocp.simulation.slack`), with the field, the
angle reached and the time. An angle outside by at most
:data:`~cable_ocp.drive.bounds.BOUND_TOLERANCE` counts as within, as for the optimiser's
solutions.
"""

from __future__ import annotations

import numpy as np

from cable_ocp.drive.bounds import BOUND_TOLERANCE


def drum_failure(winch, time: np.ndarray, angle: np.ndarray) -> str | None:
    """Where a run's drum went furthest beyond its range, or None if it never did.

    Parameters
    ----------
    winch : Winch
        The scene's winch (``angle_min``, ``angle_max``, rad).
    time : array (k,), s
    angle : array (k,), rad
        The drum angle at ``time``, heave compensation included.

    Returns
    -------
    str or None
        ``the drum turned to 35.2 rad at t = 12 s, beyond winch.angle_max = 24 rad`` for the
        sample furthest outside, with how long the drum stayed outside.
    """
    angle = np.asarray(angle, dtype=float)
    excess = np.maximum(winch.angle_min - angle, angle - winch.angle_max)
    outside = excess > BOUND_TOLERANCE
    if not outside.any():
        return None
    k = int(np.argmax(np.where(outside, excess, -np.inf)))
    field, bound = (
        ("angle_max", winch.angle_max)
        if angle[k] > winch.angle_max
        else ("angle_min", winch.angle_min)
    )
    return (
        f"the drum turned to {angle[k]:.4g} rad at t = {time[k]:g} s, beyond winch.{field} = "
        f"{bound:g} rad (outside from t = {time[int(np.argmax(outside))]:g} s, "
        f"{np.count_nonzero(outside)} of {time.size} samples): the scene's drum cannot turn there"
    )
