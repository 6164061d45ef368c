"""The current at a depth: uniform, or a profile table ``z -> (u, v)`` interpolated in z.

A profile is a table of rows ``(z_k, u_k, v_k)`` from the surface down (``z_0 > z_1 > ...``, m,
z up with the sea surface at 0; ``u, v`` the x and y components, m/s). Between two rows the
current is linear in z; above the first row and below the last it keeps that row's value. It is
written as a sum of ramps,

    c(z) = c_0 + sum_k (c_{k+1} - c_k) clip((z_k - z) / (z_k - z_{k+1}), 0, 1),

the same formula in CasADi (the model's drag, :func:`current_at`) and in numpy (the statics'
first guess, :func:`current_values`). A table whose rows all carry one current never gets here:
it is that uniform current (``cable_ocp.model.cable``). Piecewise linear, not smoothed: the
drag's derivative in z jumps at the rows (a kink of the force, not a jump).
"""

from __future__ import annotations

import casadi as ca
import numpy as np


def current_at(hydro, z: ca.SX) -> ca.SX:
    """Current velocity (3, m/s) at the height ``z`` (m) of a point of the cable.

    Parameters
    ----------
    hydro : HydroCoefficients
        ``current`` (uniform, used when ``current_z`` is empty) or the profile ``current_z``,
        ``current_u``, ``current_v``.
    z : SX
        Height of the point (m, negative under water).
    """
    if not hydro.current_z:
        return ca.vertcat(*hydro.current)
    ramps = _ramps(hydro.current_z, z, lambda s: ca.fmin(ca.fmax(s, 0.0), 1.0))
    u = _ramp_sum(hydro.current_u, ramps)
    v = _ramp_sum(hydro.current_v, ramps)
    return ca.vertcat(u, v, 0.0)


def current_values(hydro, z: np.ndarray) -> np.ndarray:
    """Current velocities (len(z), 3), m/s, at the heights ``z`` (m): numpy's :func:`current_at`."""
    z = np.asarray(z, dtype=float)
    if not hydro.current_z:
        return np.tile(np.asarray(hydro.current, dtype=float), (z.size, 1))
    ramps = _ramps(hydro.current_z, z.ravel(), lambda s: np.clip(s, 0.0, 1.0))
    u = _ramp_sum(hydro.current_u, ramps)
    v = _ramp_sum(hydro.current_v, ramps)
    return np.column_stack([u, v, np.zeros(z.size)])


def has_current(hydro) -> bool:
    """Whether the water moves anywhere (numbers, not symbols)."""
    return bool(np.any(hydro.current) or np.any(hydro.current_u) or np.any(hydro.current_v))


def _ramps(heights, z, clip) -> list:
    """``clip((z_k - z) / (z_k - z_{k+1}))`` for each pair of neighbouring rows."""
    return [
        clip((upper - z) / (upper - lower))
        for upper, lower in zip(heights[:-1], heights[1:], strict=True)
    ]


def _ramp_sum(values, ramps):
    """``c_0 + sum_k (c_{k+1} - c_k) ramp_k``."""
    total = values[0]
    for k, ramp in enumerate(ramps):
        total = total + (values[k + 1] - values[k]) * ramp
    return total
