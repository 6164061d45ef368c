"""Seabed height under the end: flat, one Gaussian hill (paper eq. 40) or a sum of hills.

The height is measured from the flat seabed (m, up). The same function serves numpy arrays and
CasADi expressions, so the optimiser differentiates the very formula the simulation reports.

The clearance ``delta`` (``seabed.clearance``) is the end's starting clearance over the seabed
under it, and the clearance the objective asks it to keep: the seabed under the start lies
``delta`` below the end, so ``e(t) = z_E(t) - z(x_E, y_E) - (z_E(0) - z(x_E(0), y_E(0)))``
(eq. 39, where the paper's seabed is flat under the start). ``delta`` cancels, so it places the
seabed (in plots) but does not change ``e(t)``, Omega or the optimal winch; ``e(0) = 0`` even where
a hill already rises under the start (the paper's form then asked for an error of the hill's
height at t = 0, which no winch can undo).
"""

from __future__ import annotations

import casadi as ca
import numpy as np


def seabed_height(hills, x, y):
    """Height of the seabed above its flat level at ``(x, y)`` (m).

    ``z(x, y) = sum_k k_k exp(-((x - x0_k)/p_k)^2 - ((y - y0_k)/q_k)^2)`` (eq. 40).

    Parameters
    ----------
    hills : sequence of Hill
        Each with ``height``, ``x0``, ``y0``, ``width_x``, ``width_y`` (m).
    x, y : array or casadi expression, m

    Returns
    -------
    array or casadi expression, m
    """
    symbolic = isinstance(x, (ca.SX, ca.MX)) or isinstance(y, (ca.SX, ca.MX))
    exp = ca.exp if symbolic else np.exp
    total = 0.0 * x
    for hill in hills:
        total = total + hill.height * exp(
            -(((x - hill.x0) / hill.width_x) ** 2) - ((y - hill.y0) / hill.width_y) ** 2
        )
    return total


def clearance_reference(hills, start) -> float:
    """``z_E(0) - z(x_E(0), y_E(0))`` (m): the end's start over the seabed's height under it.

    Parameters
    ----------
    start : array (3,) or longer (a state: its first three entries), m
    """
    return float(start[2] - seabed_height(hills, start[0], start[1]))


def clearance_error(hills, end_positions: np.ndarray) -> np.ndarray:
    """Deviation of the end from the clearance ``delta`` over the seabed, ``e(t)`` (eq. 39), m.

    ``e = z_E(t) - z(x_E(t), y_E(t)) - (z_E(0) - z(x_E(0), y_E(0)))``: the end starts ``delta``
    above the seabed under it and should stay ``delta`` above the seabed, which may rise under
    it. ``delta`` cancels, so it is not an argument.

    Parameters
    ----------
    end_positions : array (k, 3), m
    """
    x, y, z = end_positions.T
    return z - seabed_height(hills, x, y) - clearance_reference(hills, end_positions[0])


def trapezoid_weights(step: float, count: int) -> np.ndarray:
    """Weights (s) of the trapezoidal rule on ``count`` points ``step`` (s) apart."""
    weights = np.full(count, step)
    weights[[0, -1]] = step / 2
    return weights


def rms_objective(time: np.ndarray, error: np.ndarray) -> float:
    """``Omega = sqrt(1/T int_0^T e^2 dt)`` (eq. 39) by the trapezoidal rule, m."""
    span = time[-1] - time[0]
    return float(np.sqrt(np.trapezoid(error**2, time) / span))
