"""Parametrisations of the winch angle ``phi(t)`` that are linear in their parameters.

Each maps a parameter vector ``p`` to ``phi(t) = B0(t) p`` with ``phi' = B1(t) p`` and
``phi'' = B2(t) p``, so the optimiser sees the winch input as an affine function of its decision
variables and the angle bounds as linear constraints.

- :class:`KnotSpline`: the paper's cubic spline through ``phi(t_i)``, ``t_i = i T / p`` (eq. 41),
  ``phi(0) = 0``; it starts at rest and ends free (as :func:`cable_ocp.drive.winch.spline_angle`).
- :class:`HermiteIntervals`: a piecewise cubic per interval of a grid, with the angle and its rate
  at the grid nodes as parameters (C1); ``phi(0) = phi'(0) = 0`` are held fixed.

Both take ``left``: where true, a time on a breakpoint is evaluated as the limit from the left. The
Hermite angle's acceleration jumps at its nodes, and an RK4 step that ends on a node must see the
acceleration of the piece it integrates over: with the right limit there, every node put a kick of
``h r_D |jump in phi''| / 6`` (m/s) into the bond rates, and the bonds drifted by 1e-4 m within
a few nodes (paper_hill with a moving winch).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.interpolate import CubicSpline

from cable_ocp.drive.winch import coming_to_rest, knot_times, spline_angle


def hermite_polynomials(s: np.ndarray) -> tuple[np.ndarray, ...]:
    """The cubic Hermite basis ``h00, h10, h01, h11`` at ``s`` in [0, 1], each (3, len(s)).

    Rows: the value and its first and second derivatives with respect to ``s``.
    """
    s = np.atleast_1d(np.asarray(s, dtype=float))
    square, cube = s**2, s**3
    # Written row by row into one array: np.vstack's checks cost as much as the polynomials
    # on the closed loop's few hundred times (same operations, the same numbers).
    rows = np.empty((4, 3, *s.shape))
    rows[0, 0], rows[0, 1], rows[0, 2] = 2 * cube - 3 * square + 1, 6 * square - 6 * s, 12 * s - 6
    rows[1, 0], rows[1, 1], rows[1, 2] = cube - 2 * square + s, 3 * square - 4 * s + 1, 6 * s - 4
    rows[2, 0], rows[2, 1], rows[2, 2] = -2 * cube + 3 * square, -6 * square + 6 * s, -12 * s + 6
    rows[3, 0], rows[3, 1], rows[3, 2] = cube - square, 3 * square - 2 * s, 6 * s - 2
    return rows[0], rows[1], rows[2], rows[3]


def hermite_values(
    k: np.ndarray, s: np.ndarray, width, angles: np.ndarray, rates: np.ndarray
) -> np.ndarray:
    """Value, rate and acceleration (3, len(s)) of a piecewise cubic Hermite angle.

    ``basis @ parameters`` without the basis rows (3x fewer operations on the closed loop's
    stage times, and a full-model run's): ``k`` each time's interval, ``s`` its place in it (0
    to 1), ``width`` (s) the intervals' width (one, or each time's), ``angles`` and ``rates``
    (rad, rad/s) at every node, node 0 included.
    """
    h00, h10, h01, h11 = hermite_polynomials(s)
    width = np.asarray(width, dtype=float)
    scale = np.stack(np.broadcast_arrays(1.0, 1.0 / width, 1.0 / width**2)).reshape(3, -1)
    return scale * (
        h00 * angles[k] + h01 * angles[k + 1] + width * (h10 * rates[k] + h11 * rates[k + 1])
    )


def hermite_rows(
    k: np.ndarray, s: np.ndarray, width, first: int, rates: int, size: int
) -> np.ndarray:
    """Basis rows (3, len(s), size) of a piecewise cubic Hermite angle: value, rate, acceleration.

    Parameters
    ----------
    k : int array
        Each time's interval (between nodes ``k`` and ``k + 1``).
    s : array
        Its place in that interval, 0 to 1.
    width : float or array like ``s``, s
        The intervals' widths (one, or each time's).
    first : int
        The first node with parameters (1 where node 0 is held at rest).
    rates : int
        Index of the first node's rate among the parameters (the nodes' angles come first).
    size : int
        Number of parameters.
    """
    width = np.broadcast_to(np.asarray(width, dtype=float), s.shape)
    h00, h10, h01, h11 = hermite_polynomials(s)
    scale = np.stack([np.ones_like(width), 1.0 / width, 1.0 / width**2])
    out = np.zeros((3, s.size, size))
    rows = np.arange(s.size)
    for node, (value_basis, rate_basis) in ((k, (h00, h10)), (k + 1, (h01, h11))):
        valid = node >= first
        column = node[valid] - first
        for d in range(3):
            factor = scale[d][valid]
            out[d, rows[valid], column] += factor * value_basis[d][valid]
            out[d, rows[valid], rates + column] += factor * width[valid] * rate_basis[d][valid]
    return out


class HermiteParameters:
    """The parameter layout of a piecewise cubic Hermite angle on ``intervals`` intervals.

    ``[phi_0..phi_N, phi'_0..phi'_N]`` at the nodes, node 0 left out (held at rest) unless
    ``free_start``; shared by :class:`HermiteIntervals` and
    :class:`cable_ocp.control.hermite_nodes.HermiteNodes`, which provide ``intervals``,
    ``free_start``, ``breakpoints`` and ``basis``.
    """

    @property
    def first_node(self) -> int:
        """The first node with parameters (1 where node 0 is held at rest)."""
        return 0 if self.free_start else 1

    @property
    def first_rate(self) -> int:
        """Index of the first node's rate among the parameters (the nodes' angles come first)."""
        return self.intervals + self.free_start

    @property
    def size(self) -> int:
        """Number of parameters."""
        return 2 * self.first_rate

    def node_indices(self, node: int) -> tuple[int, int]:
        """Indices of the angle and the rate of ``node`` (0 .. intervals) in the parameters."""
        first = self.first_node
        if node < first:
            raise ValueError(f"node {node} is held at rest: it has no parameters")
        return node - first, self.first_rate + node - first

    def node_values(self, parameters: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Angles and rates (rad, rad/s) at every node, node 0 included."""
        parameters = np.asarray(parameters, dtype=float)
        first, split = self.first_node, self.first_rate
        angles, rates = np.zeros(self.intervals + 1), np.zeros(self.intervals + 1)
        angles[first:], rates[first:] = parameters[:split], parameters[split:]
        return angles, rates

    def rows(self, k: np.ndarray, s: np.ndarray, width) -> np.ndarray:
        """Basis rows (3, len(s), size) of times in intervals ``k`` at places ``s`` (0 to 1).

        ``width`` (s): the intervals' width, one or each time's (:func:`hermite_rows`).
        """
        return hermite_rows(k, s, width, self.first_node, self.first_rate, self.size)

    def resampled(self, parameters: np.ndarray, offset: float) -> np.ndarray:
        """Free-start parameters of the same angle moved on by ``offset`` (s): a warm start.

        The new nodes take the angle and rate at ``offset + t_k``: exact where the nodes fall on
        old ones (an offset of whole intervals of a uniform grid), a C1 interpolation between
        them otherwise; beyond the old end it follows the extension that comes to rest.
        """
        if not self.free_start:
            raise ValueError("only a free-start control (a receding horizon) can be resampled")
        b0, b1, _ = self.basis(offset + self.breakpoints)
        return np.concatenate([b0 @ parameters, b1 @ parameters])


@dataclass(frozen=True)
class KnotSpline:
    """The paper's cubic spline through ``knots`` values (rad) on ``[0, duration]`` (s)."""

    duration: float
    knots: int

    @property
    def size(self) -> int:
        """Number of parameters."""
        return self.knots

    @property
    def breakpoints(self) -> np.ndarray:
        """Times (s) between which the angle is one cubic polynomial: the knots."""
        return knot_times(self.duration, self.knots)

    def basis(self, t: np.ndarray, left=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``B0, B1, B2`` at the times ``t``: arrays (len(t), size).

        ``left`` is accepted for a uniform interface; the spline is C2, both limits agree.
        """
        t = np.clip(np.atleast_1d(np.asarray(t, dtype=float)), 0.0, self.duration)
        values = np.vstack([np.zeros(self.knots), np.eye(self.knots)])
        zeros = np.zeros(self.knots)
        spline = CubicSpline(
            knot_times(self.duration, self.knots), values, bc_type=((1, zeros), (2, zeros))
        )
        return spline(t), spline(t, 1), spline(t, 2)

    def angle_function(self, parameters: np.ndarray):
        """The winch angle history of a parameter vector."""
        return spline_angle(self.duration, parameters)


@dataclass(frozen=True)
class HermiteIntervals(HermiteParameters):
    """Piecewise cubic Hermite angle on ``intervals`` equal intervals of ``[0, duration]``.

    Parameters are ``[phi_1..phi_N, phi'_1..phi'_N]`` at the nodes ``t_k = k T / N``, node 0
    being held at ``phi = phi' = 0`` (the winch at rest at the start). With ``free_start`` (a
    receding horizon, which starts where the winch is) node 0 is a parameter too:
    ``[phi_0..phi_N, phi'_0..phi'_N]``. Beyond ``duration`` (where a closed loop holds a plan
    after its last successful solve) the angle continues C2 and comes to rest
    (:func:`~cable_ocp.drive.winch.coming_to_rest`, ``c`` one interval; holding the end value
    opened the plant's bonds one horizon after the last solve).
    """

    duration: float
    intervals: int
    free_start: bool = False

    @property
    def breakpoints(self) -> np.ndarray:
        """Times (s) between which the angle is one cubic polynomial: the nodes."""
        return np.linspace(0.0, self.duration, self.intervals + 1)

    def basis(self, t: np.ndarray, left=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``B0, B1, B2`` at the times ``t``: arrays (len(t), size).

        A time on a node belongs to the interval that starts there (the last node to the last
        interval), or, where ``left`` (bool, or array like ``t``) is true, to the interval that
        ends there (node 0 to the first). Beyond ``duration``: the C2 extension (class docstring).
        """
        t_given, beyond, k, s = self._located(t, left)
        out = self.rows(k, s, self.duration / self.intervals)
        if np.any(beyond):
            out[:, beyond] = self._extension(out[:, beyond], (t_given[beyond] - self.duration))
        return out[0], out[1], out[2]

    def evaluate(
        self, parameters: np.ndarray, t: np.ndarray, left=None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Angle, rate and acceleration (rad, rad/s, rad/s^2) at the times ``t`` (s).

        ``basis(t, left) @ parameters`` without the basis: the closed loop evaluates its plans
        at every sample's stage times, where the basis's (3, len(t), size) rows cost 3x more.
        """
        t_given, beyond, k, s = self._located(t, left)
        out = hermite_values(k, s, self.duration / self.intervals, *self.node_values(parameters))
        if beyond.any():
            tail = self._extension(out[:, beyond, None], (t_given[beyond] - self.duration))
            out[:, beyond] = tail[..., 0]
        return out[0], out[1], out[2]

    def _located(self, t: np.ndarray, left) -> tuple[np.ndarray, np.ndarray, np.ndarray, ...]:
        """The times ``t`` (s) as given, which lie beyond the end, their intervals and place.

        A time on a node belongs to the interval that starts there, or to the one that ends
        there where ``left`` is true (:meth:`basis`); a time beyond the end to the last one.
        """
        t = t_given = np.atleast_1d(np.asarray(t, dtype=float))
        beyond = t > self.duration * (1 + 1e-9)
        t = t.clip(0.0, self.duration)
        if left is not None:
            left = np.where(beyond, True, left)  # the end's rows from the last interval
        width = self.duration / self.intervals
        k = (t / width + 1e-9).astype(int)
        if left is not None:
            k = np.where(left, np.ceil(t / width - 1e-9).astype(int) - 1, k)
        k = np.clip(k, 0, self.intervals - 1)
        return t_given, beyond, k, t / width - k

    def _extension(self, end: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """Rows (3, k, size) of the angle ``tau`` (s) past the end, from its rows there."""
        return np.stack(coming_to_rest(*end, tau[:, None], self.duration / self.intervals))

    def angle_function(self, parameters: np.ndarray):
        """The winch angle history of a parameter vector (it takes ``left`` as :meth:`basis`)."""
        parameters = np.asarray(parameters, dtype=float).ravel()

        def angle(t, left=None):
            return self.evaluate(parameters, t, left)

        return angle
