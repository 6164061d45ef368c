"""A piecewise cubic Hermite winch angle on nodes at any times (the adaptive grid's control).

:class:`HermiteNodes` is :class:`~cable_ocp.drive.controls.HermiteIntervals` on nodes
``0 = t_0 < t_1 < ... < t_K = T`` that need not be equally spaced: the angle and its rate at
``t_1 .. t_K`` are the parameters, ``phi(0) = phi'(0) = 0`` held fixed (or, with ``free_start``, a
receding horizon's plan, node 0's too: a closed loop's plan with a shorter first interval,
``MpcSettings.first_interval``), the angle C1 with its acceleration jumping at the nodes (so each
node must fall on an RK4 step end of every model that runs it:
:mod:`cable_ocp.control.adaptive_grid` takes them from the uniform default grid). The same interface
as the other controls (``size``, ``breakpoints``, ``basis``, ``evaluate``, ``angle_function``, and a
receding horizon's ``node_indices`` and ``resampled``), with ``left`` as theirs; beyond ``T`` the
angle comes to rest C2 over one last interval (:func:`~cable_ocp.drive.winch.coming_to_rest`). A
uniform grid keeps ``HermiteIntervals``, so that today's optima stay bit for bit.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cable_ocp.drive.controls import HermiteParameters, hermite_values
from cable_ocp.drive.winch import coming_to_rest

# Share of the shortest interval within which a time counts as on a node.
ON_NODE = 1e-9


def check_nodes(nodes, duration: float, name: str = "GridSettings.nodes") -> np.ndarray:
    """Node times (s) from 0 to ``duration``, strictly increasing, as an array.

    Raises
    ------
    ValueError
        Naming ``name``: fewer than two nodes, not finite, not increasing, or not from 0 to T.
    """
    times = np.asarray(nodes, dtype=float).ravel()
    if times.size < 2 or not np.all(np.isfinite(times)):
        raise ValueError(f"{name}: at least two finite node times (s), 0 first and T last")
    if np.any(np.diff(times) <= 0):
        raise ValueError(f"{name}: node times must increase strictly")
    scale = max(duration, 1.0)
    if abs(times[0]) > 1e-9 * scale or abs(times[-1] - duration) > 1e-9 * scale:
        raise ValueError(
            f"{name} run from {times[0]:g} to {times[-1]:g} s: they must run from 0 to "
            f"numerics.duration = {duration:g} s"
        )
    times[0], times[-1] = 0.0, duration
    return times


@dataclass(frozen=True, eq=False)
class HermiteNodes(HermiteParameters):
    """Piecewise cubic Hermite angle on the nodes ``times`` (s, from 0 to the duration).

    Parameters are ``[phi_1..phi_K, phi'_1..phi'_K]`` at ``t_1 .. t_K``, with ``free_start``
    ``[phi_0..phi_K, phi'_0..phi'_K]`` (module docstring).
    """

    times: np.ndarray
    free_start: bool = False

    def __post_init__(self):
        times = np.asarray(self.times, dtype=float)
        object.__setattr__(self, "times", check_nodes(times, float(times[-1]), "nodes"))

    @property
    def duration(self) -> float:
        """The horizon T (s): the last node."""
        return float(self.times[-1])

    @property
    def intervals(self) -> int:
        """Number of intervals ``K``."""
        return self.times.size - 1

    @property
    def breakpoints(self) -> np.ndarray:
        """Times (s) between which the angle is one cubic polynomial: the nodes."""
        return self.times.copy()

    @property
    def widths(self) -> np.ndarray:
        """The intervals' widths (s)."""
        return np.diff(self.times)

    def basis(self, t: np.ndarray, left=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``B0, B1, B2`` at the times ``t``: arrays (len(t), size).

        A time on a node belongs to the interval that starts there (the last node to the last
        interval), or, where ``left`` (bool, or array like ``t``) is true, to the one that ends
        there (node 0 to the first); beyond the duration, the extension that comes to rest.
        """
        t_given, beyond, k, s = self._located(t, left)
        out = self.rows(k, s, self.widths[k])
        if np.any(beyond):
            out[:, beyond] = self._extension(out[:, beyond], t_given[beyond] - self.duration)
        return out[0], out[1], out[2]

    def evaluate(
        self, parameters: np.ndarray, t: np.ndarray, left=None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Angle, rate and acceleration (rad, rad/s, rad/s^2) at the times ``t`` (s).

        ``basis(t, left) @ parameters`` without the basis (a sixth of its time on a full-model
        run's stage times).
        """
        t_given, beyond, k, s = self._located(t, left)
        out = hermite_values(k, s, self.widths[k], *self.node_values(parameters))
        if beyond.any():
            tail = self._extension(out[:, beyond, None], t_given[beyond] - self.duration)
            out[:, beyond] = tail[..., 0]
        return out[0], out[1], out[2]

    def _located(self, t: np.ndarray, left) -> tuple[np.ndarray, np.ndarray, np.ndarray, ...]:
        """The times ``t`` (s) as given, which lie beyond the end, their intervals and place."""
        t = t_given = np.atleast_1d(np.asarray(t, dtype=float))
        beyond = t > self.duration * (1 + 1e-9)
        t = t.clip(0.0, self.duration)
        tolerance = ON_NODE * float(np.min(self.widths))
        k = np.searchsorted(self.times, t + tolerance, side="right") - 1
        if left is not None:
            left = np.where(beyond, True, left)  # the end's rows from the last interval
            k = np.where(left, np.searchsorted(self.times, t - tolerance, side="left") - 1, k)
        k = np.clip(k, 0, self.intervals - 1)
        return t_given, beyond, k, (t - self.times[k]) / self.widths[k]

    def _extension(self, end: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """Rows (3, k, size) of the angle ``tau`` (s) past the end, from its rows there."""
        return np.stack(coming_to_rest(*end, tau[:, None], float(self.widths[-1])))

    def angle_function(self, parameters: np.ndarray):
        """The winch angle history of a parameter vector (it takes ``left`` as :meth:`basis`)."""
        parameters = np.asarray(parameters, dtype=float).ravel()

        def angle(t, left=None):
            return self.evaluate(parameters, t, left)

        return angle
