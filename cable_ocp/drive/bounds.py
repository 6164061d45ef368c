"""Winch bounds on a control, held everywhere in time, not only at the samples.

A control (:mod:`cable_ocp.drive.controls`) makes the winch angle a cubic polynomial of time on each
piece between its breakpoints, linear in the parameters ``p``. On a sub-interval ``[a, b]`` of one
piece, a polynomial of degree d lies inside the range of its d + 1 Bernstein coefficients, which are
linear in ``p`` too. Bounding these coefficients bounds the angle (d = 3), its rate (d = 2) and its
acceleration (d = 1) on the whole sub-interval: linear constraints that are sufficient, and
conservative only by about ``w^2 |phi''| / 8`` on sub-intervals of width ``w`` (3e-4 rad for
``w = 0.5 s`` and ``|phi''| = 0.01 rad/s^2``).

The angle bound applies to the angle the winch turns to, heave compensation included (``z_A / r_D``,
eq. 38); on each sub-interval the heave part is bounded by its extreme of 17 samples, widened by
``|z''| d^2 / 8`` (``d`` the samples' spacing, ``|z''|`` the largest second derivative of the heave
part at them): the most a smooth function rises between two samples (the samples alone had let a
whole-space scene's drum pass its bound between them, seed 2 case 2). The rate and
acceleration bounds (``winch.rate_max``, ``winch.acceleration_max``) apply to the commanded profile,
the heave compensation comes on top.

:func:`violation` is the check after a solve: the exact extrema of every polynomial piece (and dense
samples of the heave part), compared with the bounds widened by :data:`BOUND_TOLERANCE`.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import cached_property
from math import comb

import numpy as np
from scipy import sparse

from cable_ocp.drive.drive import Drive

# Violation of a winch bound that a solution may show and still count as within it: rad for the
# angle, rad/s for the rate, rad/s^2 for the acceleration (the top-element length: r_D times it, m).
# Solvers get bounds tightened by half of it, so IPOPT's bound relaxation (1e-8 relative) and
# round-off stay inside.
BOUND_TOLERANCE = 1e-6
# Samples per sub-interval of the heave-compensation part of the angle.
HEAVE_SAMPLES = 17
NAMES = ("winch angle phi", "winch rate phi'", "winch acceleration phi''")
UNITS = ("rad", "rad/s", "rad/s^2")


def angle_bounds(scene) -> tuple[float, float]:
    """Winch-angle range (rad) from the angle bounds and the top-element length bounds.

    The scene's mesh gives the top element the winch's whole haul-in (``Scene.mesh``), so the
    range is the winch's own unless ``winch.top_length_max`` cuts the pay-out.
    """
    w = scene.winch
    top = scene.top_element_length
    low = max(w.angle_min, (w.top_length_min - top) / w.drum_radius)
    high = w.angle_max
    if w.top_length_max is not None:
        high = min(high, (w.top_length_max - top) / w.drum_radius)
    if low > 0 or high < 0:
        raise ValueError(
            f"winch bounds leave no room around phi(0) = 0: the angle range is [{low}, {high}] rad "
            "(winch.angle_min/max with winch.top_length_min/max)"
        )
    return low, high


def winch_limits(scene) -> list[tuple[int, float, float, str]]:
    """The bounds that apply: ``(derivative, low, high, scene fields)`` for angle, rate, acc."""
    w = scene.winch
    low, high = angle_bounds(scene)
    limits = [(0, low, high, "winch.angle_min/max with winch.top_length_min/max")]
    if w.rate_max is not None:
        limits.append((1, -w.rate_max, w.rate_max, "winch.rate_max"))
    if w.acceleration_max is not None:
        limits.append((2, -w.acceleration_max, w.acceleration_max, "winch.acceleration_max"))
    return limits


def subintervals(control, grid: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Starts and ends (s) of the pieces of ``control`` cut further at the times ``grid``."""
    duration = control.duration
    points = np.union1d(control.breakpoints, np.clip(grid, 0.0, duration))
    keep = np.concatenate([[True], np.diff(points) > 1e-9 * duration])
    points = points[keep]
    points[-1] = duration
    return points[:-1], points[1:]


def bernstein_count(derivative: int) -> int:
    """Bernstein coefficients per sub-interval of a cubic's ``derivative``-th derivative."""
    return 4 - derivative


def bernstein_rows(control, starts, ends, derivative: int) -> np.ndarray:
    """Bernstein coefficients of the ``derivative``-th derivative per sub-interval.

    Returns an array (m, d + 1, control.size), d = 3 - derivative: coefficient j of sub-interval i
    is ``rows[i, j] @ p``. The coefficients come from d + 1 interior samples, so a derivative that
    jumps at a breakpoint is taken from the side of the sub-interval.
    """
    degree = bernstein_count(derivative) - 1
    s = (np.arange(degree + 1) + 0.5) / (degree + 1)
    j = np.arange(degree + 1)
    binomials = np.array([comb(degree, k) for k in j])
    vandermonde = binomials * s[:, None] ** j * (1 - s[:, None]) ** (degree - j)
    times = starts[:, None] + s[None, :] * (ends - starts)[:, None]
    values = control.basis(times.ravel())[derivative].reshape(starts.size, degree + 1, -1)
    return np.einsum("ji,mik->mjk", np.linalg.inv(vandermonde), values)


def _bound_matrix(scene, control, starts: np.ndarray, ends: np.ndarray) -> np.ndarray:
    """The rows of :class:`LinearBounds` on the sub-intervals: each bound's in turn."""
    blocks = [
        bernstein_rows(control, starts, ends, derivative).reshape(-1, control.size)
        for derivative, *_ in winch_limits(scene)
    ]
    return np.vstack(blocks)


def _heave(scene, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Heave-compensation part of the winch angle at the times, and its second derivative.

    Returns (rad, rad/s^2), zeros without heave compensation.
    """
    angle, _, acceleration = Drive.from_scene(scene).winch_angle(times)
    return angle, acceleration


def _heave_range(scene, starts: np.ndarray, ends: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The heave part's lowest and highest angle (rad) on each sub-interval ``[start, end]``.

    The extremes of :data:`HEAVE_SAMPLES` samples, widened by ``|z''| d^2 / 8`` (module
    docstring): between samples ``d`` apart a function whose second derivative stays within
    ``|z''|`` rises at most that far above them.
    """
    fraction = np.linspace(0.0, 1.0, HEAVE_SAMPLES)
    samples = starts[:, None] + fraction * (ends - starts)[:, None]
    heave, curvature = (part.reshape(samples.shape) for part in _heave(scene, samples.ravel()))
    spacing = (ends - starts) / (HEAVE_SAMPLES - 1)
    reach = np.abs(curvature).max(axis=1) * spacing**2 / 8
    return heave.min(axis=1) - reach, heave.max(axis=1) + reach


def shrunk(lower, upper, margin) -> tuple[np.ndarray, np.ndarray]:
    """Limits moved ``margin`` inside, or a quarter of the range where it is narrower.

    A range narrower than twice the margin (a winch locked to +-1e-5 rad, a rate limit of
    1e-6 rad/s) would otherwise be inverted, and a QP solver would refuse it as ill-posed.
    All arguments broadcast (rad, rad/s or rad/s^2).
    """
    lower, upper = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    width = np.where(np.isfinite(upper - lower), np.maximum(upper - lower, 0.0), np.inf)
    inside = np.minimum(margin, width / 4)
    return lower + inside, upper - inside


@dataclass(frozen=True)
class LinearBounds:
    """Linear constraints ``lower <= matrix @ p <= upper`` that hold the winch bounds everywhere.

    Attributes
    ----------
    matrix : array (rows, size)
    lower, upper : array (rows,)
        In rad, rad/s or rad/s^2 per row, tightened by the margin.
    derivatives : array of int (rows,)
        What each row bounds: 0 the angle, 1 its rate, 2 its acceleration.
    starts : array (rows,), s
        Start of the sub-interval each row holds on.
    """

    matrix: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    derivatives: np.ndarray
    starts: np.ndarray

    @cached_property
    def sparse_matrix(self) -> sparse.csr_array:
        """:attr:`matrix` as a sparse array, made once.

        Each row holds one sub-interval's cubic: a few nonzeros.
        """
        return sparse.csr_array(self.matrix)

    @classmethod
    def build(cls, scene, control, grid: np.ndarray, margin: float = BOUND_TOLERANCE / 2):
        """Constraints of the scene's winch bounds on ``control``, cut at the times ``grid``."""
        starts, ends = subintervals(control, grid)
        lowest, highest = _heave_range(scene, starts, ends)
        lower, upper, derivatives, times = [], [], [], []
        for derivative, low, high, _ in winch_limits(scene):
            count = bernstein_count(derivative)
            shift_low = lowest if derivative == 0 else np.zeros(starts.size)
            shift_high = highest if derivative == 0 else np.zeros(starts.size)
            low, high = shrunk(low - shift_low, high - shift_high, margin)
            lower.append(np.repeat(low, count))
            upper.append(np.repeat(high, count))
            derivatives.append(np.full(starts.size * count, derivative))
            times.append(np.repeat(starts, count))
        return cls(
            _bound_matrix(scene, control, starts, ends),
            np.concatenate(lower),
            np.concatenate(upper),
            np.concatenate(derivatives),
            np.concatenate(times),
        )

    def on_control(self, scene, control, grid: np.ndarray) -> LinearBounds:
        """These constraints on another control of the same scene, cut at the same ``grid``.

        Where both controls cut ``grid`` into the same sub-intervals (their breakpoints are on
        it: the adaptive grid's candidates), the limits are these (the heave's extremes are not
        sampled again: 0.1-0.2 s of vessel motion on a 415 s whole-space case) and only the
        rows are the new control's; otherwise they are built anew (:meth:`build`).
        """
        starts, ends = subintervals(control, grid)
        if not np.array_equal(np.unique(self.starts), starts):
            return LinearBounds.build(scene, control, grid)
        return replace(self, matrix=_bound_matrix(scene, control, starts, ends))

    def narrowed(self, margin: float, ramp: float) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper limits with the angle range narrowed by ``margin`` (rad) on each side.

        The narrowing is phased in linearly over the first ``ramp`` seconds (a receding plan
        starts where the winch is, which may be inside the margin); it takes at most a quarter
        of the range from each side (:func:`shrunk`).
        """
        share = np.clip(self.starts / ramp, 0.0, 1.0) * (self.derivatives == 0)
        return shrunk(self.lower, self.upper, margin * share)

    def excess(
        self,
        parameters: np.ndarray,
        lower: np.ndarray | None = None,
        upper: np.ndarray | None = None,
        rows: np.ndarray | None = None,
    ) -> float:
        """Largest violation of the constraints by ``parameters`` (0 when they hold).

        ``lower``, ``upper`` replace the limits (a closed loop's narrowed range); ``rows`` (a
        boolean mask) keeps only some constraints (those of a plan's first sample).
        """
        lower = self.lower if lower is None else lower
        upper = self.upper if upper is None else upper
        matrix = self.matrix
        if rows is not None:
            matrix, lower, upper = matrix[rows], lower[rows], upper[rows]
        values = matrix @ parameters
        return float(max(np.max(lower - values, initial=0.0), np.max(values - upper, initial=0.0)))

    def scale_into(self, parameters: np.ndarray) -> np.ndarray:
        """``s * parameters`` with the largest ``s`` in [0, 1] that satisfies the constraints.

        The winch at rest (``p = 0``) satisfies them whenever the heave compensation alone stays
        within the angle bounds; otherwise ``p = 0`` is returned.
        """
        values = self.matrix @ parameters
        if np.any(self.lower > 0) or np.any(self.upper < 0):
            return np.zeros_like(parameters)
        with np.errstate(divide="ignore", invalid="ignore"):
            limits = np.where(values > 0, self.upper / values, np.inf)
            limits = np.minimum(limits, np.where(values < 0, self.lower / values, np.inf))
        return min(1.0, float(limits.min())) * parameters


def _piece_extrema(angle, starts, ends, derivative):
    """Times and values of the extrema of each polynomial piece of a derivative of the angle.

    ``angle(t)`` gives the angle, rate and acceleration (a control's ``angle_function``).
    Candidates are both ends of each piece and the roots of its derivative inside it.
    """
    degree = bernstein_count(derivative) - 1
    s = (np.arange(degree + 1) + 0.5) / (degree + 1)
    times = starts[:, None] + s[None, :] * (ends - starts)[:, None]
    values = angle(times.ravel())[derivative].reshape(times.shape)
    power = values @ np.linalg.inv(np.vander(s, degree + 1, increasing=True)).T  # c0 + c1 s + ...
    candidates = [np.zeros(starts.size), np.ones(starts.size)]
    if degree == 3:  # roots of c1 + 2 c2 s + 3 c3 s^2
        a, b, c = 3 * power[:, 3], 2 * power[:, 2], power[:, 1]
        disc = np.sqrt(np.maximum(b**2 - 4 * a * c, 0.0))
        with np.errstate(divide="ignore", invalid="ignore"):
            quadratic = [(-b + disc) / (2 * a), (-b - disc) / (2 * a)]
            linear = -c / b
        cubic = np.abs(a) > 1e-14 * np.abs(b) + 1e-300
        candidates += [np.where(cubic, root, linear) for root in quadratic]
    elif degree == 2:  # root of c1 + 2 c2 s
        with np.errstate(divide="ignore", invalid="ignore"):
            candidates.append(-power[:, 1] / (2 * power[:, 2]))
    points = np.stack(candidates, axis=1)
    points = np.where(np.isfinite(points), np.clip(points, 0.0, 1.0), 0.0)
    extreme = np.einsum("mk,mjk->mj", power, points[:, :, None] ** np.arange(degree + 1))
    return (starts[:, None] + points * (ends - starts)[:, None]).ravel(), extreme.ravel()


def violation(scene, control, parameters, grid: np.ndarray | None = None) -> str | None:
    """Why the winch of ``parameters`` breaks a bound by more than the tolerance (None if not).

    Checks the exact extrema of the angle, rate and acceleration of every polynomial piece; with
    heave compensation, the angle also at 17 samples per piece or ``grid`` step.
    """
    angle = control.angle_function(np.asarray(parameters, dtype=float).ravel())
    starts, ends = subintervals(control, np.zeros(0) if grid is None else grid)
    for derivative, low, high, fields in winch_limits(scene):
        times, values = _piece_extrema(angle, starts, ends, derivative)
        if derivative == 0 and scene.top.heave_compensated:
            dense = starts[:, None] + np.linspace(0, 1, HEAVE_SAMPLES) * (ends - starts)[:, None]
            dense = dense.ravel()
            times = np.concatenate([times, dense])
            values = np.concatenate([values, angle(dense)[0]])
            values = values + _heave(scene, times)[0]
        excess = np.maximum(low - values, values - high)
        k = int(np.argmax(excess))
        if excess[k] > BOUND_TOLERANCE:
            return (
                f"{NAMES[derivative]} = {values[k]:.10g} {UNITS[derivative]} at t = {times[k]:.6g} "
                f"s is outside [{low:.10g}, {high:.10g}] {UNITS[derivative]} ({fields}) by "
                f"{excess[k]:.3g} {UNITS[derivative]}, more than the tolerance {BOUND_TOLERANCE:g}"
            )
    return None
