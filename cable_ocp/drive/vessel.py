"""Prescribed motion of the top point ``A_{n+1}`` (the winch on the vessel), with exact rates.

Every motion is a callable ``t -> (position, velocity, acceleration)``, each an array of shape
``(3, len(t))`` in m, m/s, m/s^2, evaluated vectorised in numpy.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np

from cable_ocp.drive.sea_state import sea_state_motion

TopMotionFunction = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray, np.ndarray]]
MIN_TABLE_ROWS = 4


def smoothstep(tau: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Quintic smoothstep ``S = 10 tau^3 - 15 tau^4 + 6 tau^5`` on [0, 1], 0 before and 1 after.

    Returns
    -------
    value, first derivative, integral from 0 : arrays (per unit tau)
    """
    s = np.clip(tau, 0.0, 1.0)
    value = s**3 * (10 - 15 * s + 6 * s**2)
    slope = 30 * s**2 * (1 - s) ** 2
    integral = s**4 * (2.5 - 3 * s + s**2) + np.maximum(tau - 1.0, 0.0) * 1.0
    return value, slope, integral


def smoothstep_curvature(tau: np.ndarray) -> np.ndarray:
    """Second derivative of :func:`smoothstep` (per unit tau squared): 0 outside [0, 1]."""
    s = np.clip(tau, 0.0, 1.0)
    return 60 * s * (1 - s) * (1 - 2 * s)


def fixed_top(start) -> TopMotionFunction:
    """Top held at ``start`` (m)."""
    start = np.asarray(start, dtype=float).reshape(3, 1)

    def motion(t):
        t = np.atleast_1d(t)
        zeros = np.zeros((3, t.size))
        return start + zeros, zeros, zeros.copy()

    return motion


def tow_profile(start, surge_speed, sway_speed, ramp_time, sway_period) -> TopMotionFunction:
    """The reconstructed vessel motion of CONVENTIONS.md §6.

    ``v_x = U S(t / T_r)``, ``v_y = W sin^2(pi t / T)``; positions are the exact integrals.

    Parameters
    ----------
    start : 3 floats, m
    surge_speed : float, m/s (U)
    sway_speed : float, m/s (W)
    ramp_time : float, s (T_r)
    sway_period : float, s (T)
    """
    start = np.asarray(start, dtype=float).reshape(3, 1)

    def motion(t):
        t = np.atleast_1d(np.asarray(t, dtype=float))
        value, slope, integral = smoothstep(t / ramp_time)
        omega = 2 * np.pi / sway_period
        sway = np.sin(omega * t)
        # Rows written into arrays, not stacked: np.vstack's checks cost as much as the motion
        # on a closed loop's sample (the same numbers).
        position, velocity, acceleration = np.empty((3, 3, t.size))
        position[0] = surge_speed * ramp_time * integral
        position[1] = sway_speed * (t / 2 - sway / (2 * omega))
        position[2] = 0.0
        velocity[0] = surge_speed * value
        velocity[1] = sway_speed * np.sin(np.pi * t / sway_period) ** 2
        velocity[2] = 0 * t
        acceleration[0] = surge_speed * slope / ramp_time
        acceleration[1] = sway_speed * omega / 2 * sway
        acceleration[2] = 0 * t
        return start + position, velocity, acceleration

    return motion


def tabulated_top(time, points) -> TopMotionFunction:
    """Top motion through a time history, interpolated by a C2 cubic spline.

    Parameters
    ----------
    time : array (k,), s
        Strictly increasing, at least 4 samples.
    points : array (k, 3), m
        Positions x, y, z.
    """
    time = np.asarray(time, dtype=float)
    points = np.asarray(points, dtype=float)
    if time.ndim != 1 or points.shape != (time.size, 3):
        raise ValueError(
            f"top.table: expected columns t, x, y, z; got times {time.shape} and points "
            f"{points.shape}"
        )
    if time.size < MIN_TABLE_ROWS:
        raise ValueError(f"top.table: {time.size} rows; need at least {MIN_TABLE_ROWS}")
    if not (np.all(np.isfinite(time)) and np.all(np.isfinite(points))):
        row = int(np.argmax(~np.isfinite(np.column_stack([time, points])).all(axis=1)))
        raise ValueError(f"top.table: row {row} has a non-finite value (NaN or inf)")
    if np.any(np.diff(time) <= 0):
        row = int(np.argmax(np.diff(time) <= 0)) + 1
        raise ValueError(f"top.table: time must increase strictly; row {row} has t = {time[row]}")
    from scipy.interpolate import CubicSpline  # here: only a tabulated motion needs SciPy

    spline = CubicSpline(time, points, axis=0, bc_type="natural")
    slope, curvature = spline.derivative(1), spline.derivative(2)

    def motion(t):
        t = np.atleast_1d(np.asarray(t, dtype=float))
        if t.min() < time[0] - 1e-12 or t.max() > time[-1] + 1e-12:
            raise ValueError(
                f"top.table covers t in [{time[0]}, {time[-1]}] s; asked for "
                f"[{t.min()}, {t.max()}] s"
            )
        return spline(t).T, slope(t).T, curvature(t).T

    return motion


def read_table(path: str | Path) -> tuple[np.ndarray, np.ndarray]:
    """Read a CSV time history with columns t, x, y, z (s, m); a header line is allowed.

    Returns
    -------
    time : array (k,), s
    points : array (k, 3), m
    """
    try:
        data = np.genfromtxt(path, delimiter=",", comments="#", names=None, skip_header=0)
    except (OSError, ValueError) as error:
        raise ValueError(f"top.table: cannot read {path}: {error}") from error
    if data.ndim == 2 and np.all(np.isnan(data[0])):
        data = data[1:]
    if data.ndim != 2 or data.shape[1] != 4:
        raise ValueError(f"top.table: {path} must have 4 columns t, x, y, z")
    return data[:, 0], data[:, 1:]


def heave(amplitude: float, period: float) -> TopMotionFunction:
    """Vertical sinusoid ``z = a sin(2 pi t / T)`` (m) added to a horizontal motion."""
    omega = 2 * np.pi / period

    def motion(t):
        t = np.atleast_1d(np.asarray(t, dtype=float))
        zeros = np.zeros((2, t.size))
        s, c = np.sin(omega * t), np.cos(omega * t)
        return (
            np.vstack([zeros, amplitude * s]),
            np.vstack([zeros, amplitude * omega * c]),
            np.vstack([zeros, -amplitude * omega**2 * s]),
        )

    return motion


def top_motion(top) -> TopMotionFunction:
    """The top motion a scene's ``[top]`` section describes (heave and sea state included)."""
    if top.motion == "fixed":
        base = fixed_top(top.start)
    elif top.motion == "tow":
        tow = top.tow_profile
        base = tow_profile(
            top.start, tow.surge_speed, tow.sway_speed, tow.ramp_time, tow.sway_period
        )
    else:
        time, points = read_table(top.table.file)
        base = tabulated_top(time, points)
    waves = []
    if top.heave is not None and top.heave.amplitude:
        waves.append(heave(top.heave.amplitude, top.heave.period))
    if top.heave is not None and top.heave.sea_state is not None:
        waves.append(sea_state_motion(top.heave.sea_state))
    if not waves:
        return base

    def motion(t):
        total = base(t)
        for wave in waves:
            total = tuple(a + b for a, b in zip(total, wave(t), strict=True))
        return total

    return motion
