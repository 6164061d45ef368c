"""A winch given to a simulation, as an angle history: locked, knots, a function or a result."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from cable_ocp.drive import winch as winch_angles

WinchSpec = None | np.ndarray | Callable


def winch_function(scene, winch: WinchSpec) -> winch_angles.WinchAngleFunction:
    """Turn a winch specification into an angle history.

    Parameters
    ----------
    winch : None, array, callable or a result
        None: locked. An array of ``scene.winch.knots`` values: the cubic spline through them
        (rad, ``phi(0) = 0``). A callable ``t -> (phi, phi', phi'')``: used as it is. A result
        of ``optimize`` or ``mpc`` (anything with a ``winch_profile(scene)`` method), or one
        retimed (``result.retimed("hold")``): its winch on this scene, the heave feedforward or
        feedback included where it rode on one (a replay).
    """
    if winch is None:
        return winch_angles.locked
    if hasattr(winch, "winch_profile"):
        return winch.winch_profile(scene)
    if callable(winch):
        return winch
    try:
        values = np.asarray(winch, dtype=float).ravel()
    except (TypeError, ValueError):
        raise ValueError(f"winch: expected {scene.winch.knots} knot angles in rad") from None
    if values.size != scene.winch.knots:
        raise ValueError(
            f"winch: {values.size} knot values given; the scene has winch.knots = "
            f"{scene.winch.knots}"
        )
    if not np.isfinite(values).all():
        k = int(np.argmin(np.isfinite(values)))
        raise ValueError(f"winch: knot value {k + 1} is {values[k]}: must be finite (rad)")
    return winch_angles.spline_angle(scene.numerics.duration, values)
