"""Seabed height under the end: flat, one Gaussian hill (paper eq. 40) or a sum of hills.

The height is measured from the flat seabed (m, up). The same function serves numpy arrays and
CasADi expressions, so the optimiser differentiates the very formula the simulation reports.

The clearance ``delta`` (``seabed.clearance``) is the paper's: the flat seabed lies ``delta`` below
the end's starting position, ``z_sb = -(z_E(0) - delta)`` (eq. 39), so ``delta`` is the end's
starting clearance and the clearance the objective asks it to keep over the seabed. In eq. 39,
``z_E + z_sb - z(x, y) - delta = z_E(t) - z_E(0) - z(x_E, y_E)``: ``delta`` cancels, so it places
the seabed (in plots) but does not change ``e(t)``, Omega or the optimal winch.
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


def clearance_error(hills, end_positions: np.ndarray) -> np.ndarray:
    """Deviation of the end from the clearance ``delta`` over the seabed, ``e(t)`` (eq. 39), m.

    ``e = z_E + z_sb - z(x_E, y_E) - delta = z_E(t) - z_E(0) - z(x_E(t), y_E(t))`` with the seabed
    depth ``z_sb = -(z_E(0) - delta)`` of eq. 39: the end starts ``delta`` above the flat seabed and
    should stay ``delta`` above the seabed, which may rise under it. ``delta`` cancels, so it is not
    an argument.

    Parameters
    ----------
    end_positions : array (k, 3), m
    """
    x, y, z = end_positions.T
    return z - z[0] - seabed_height(hills, x, y)


def rms_objective(time: np.ndarray, error: np.ndarray) -> float:
    """``Omega = sqrt(1/T int_0^T e^2 dt)`` (eq. 39) by the trapezoidal rule, m."""
    span = time[-1] - time[0]
    return float(np.sqrt(np.trapezoid(error**2, time) / span))
