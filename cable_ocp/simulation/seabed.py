"""The seabed under the end and the clearance the objective asks the end to keep (eq. 39, 40).

The seabed is the scene's ``[seabed]`` section (:class:`~cable_ocp.scene.schema.Seabed`): a sum of
Gaussian hills (eq. 40), plus, when it names one, a bathymetry grid interpolated by a bicubic
B-spline (C2; CasADi's ``bspline``, its coefficients fitted by SciPy). Every function here also
takes a plain sequence of hills, a relative seabed. The same formulas serve numpy arrays and
CasADi SX/MX expressions, so the optimiser differentiates exactly what the simulation reports.

Two kinds of seabed (CONVENTIONS.md §5):

- **relative** (no grid, the paper's): heights above a flat level that lies ``delta``
  (``seabed.clearance``) below the end's start, so
  ``e(t) = z_E(t) - z(x_E, y_E) - (z_E(0) - z(x_E(0), y_E(0)))``. ``delta`` cancels: it places
  the seabed (in plots) but changes neither ``e(t)``, Omega nor the optimal winch; ``e(0) = 0``
  even where a hill rises under the start (the paper's form then asked for an error of the hill's
  height at t = 0, which no winch can undo);
- **absolute** (a grid): elevations, z up from the sea surface, and ``delta`` is the target,
  ``e(t) = z_E(t) - z(x_E, y_E) - delta``, from the hanging start on: ``e(0)`` is the start's
  offset from the target, which Omega counts.

Either way ``e(t) = z_E - z(x_E, y_E) - r`` with the reference ``r`` of
:func:`clearance_reference`, and the clearance (height of the end above the seabed) is
``z_E - z_sb = delta + e(t)``. Numerically, a point off the grid raises :class:`OffGridError`;
symbolically the grid is held at its edge values outside (so a solver iterate that strays stays
defined), and the verification's simulation judges the path.
"""

from __future__ import annotations

import functools

import casadi as ca
import numpy as np
from scipy.interpolate import make_interp_spline

from cable_ocp.scene.bathymetry import BathymetryGrid, read_grid
from cable_ocp.simulation.integrate import SimulationError
from cable_ocp.simulation.progress import Progress

DEGREE = 3  # bicubic
LARGE_GRID_POINTS = 1_000_000  # a grid this large shows a progress bar while its spline is built
# How far (m) the end may be under the seabed before a run is no picture of the scene: the
# bicubic grid's rounding is far below it, a rope through the ground far above.
PENETRATION_TOLERANCE = 1e-3


class OffGridError(SimulationError):
    """The end (or a point asked for) left the bathymetry grid, or started under the seabed."""


def bathymetry(seabed) -> BathymetryGrid | None:
    """The grid a ``[seabed]`` section names (read once per file), or None (also for hills)."""
    grid = getattr(seabed, "grid", None)
    return None if grid is None else read_grid(grid.file, grid.variable)


def _parts(seabed) -> tuple[tuple, BathymetryGrid | None]:
    """The hills and the grid (or None) of a ``[seabed]`` section or a sequence of hills."""
    if hasattr(seabed, "hills"):
        return seabed.hills, bathymetry(seabed)
    return tuple(seabed), None


@functools.lru_cache(maxsize=16)
def grid_surface(grid: BathymetryGrid) -> ca.Function:
    """The grid's bicubic B-spline interpolant ``z(x, y)`` (m), a CasADi Function of ``[x; y]``.

    The spline is the one of CasADi's ``interpolant(..., "bspline")`` (not-a-knot, C2), with its
    coefficients fitted here: the tensor-product fit is one banded solve along x for every row and
    one along y for every column (:func:`spline_coefficients`), linear in the grid's size, where
    CasADi's own fit solves one sparse system over the whole grid (11 s at 500 x 500, 119 s and
    1.2 GB at 800 x 800, more than 900 s at 1500 x 1500; here 0.08 s and 0.4 s). On the survey
    grid it is CasADi's fit to 3e-11 m. The Function is one node in SX and MX expressions, with
    CasADi's exact derivatives of the spline. A grid of :data:`LARGE_GRID_POINTS` or more shows
    its build as a progress bar.
    """
    progress = Progress("bathymetry", 3, quiet=grid.elevation.size < LARGE_GRID_POINTS)
    along_x = make_interp_spline(grid.x, grid.elevation, k=DEGREE, axis=0)
    progress.update(1, "fitted along x")
    along_y = make_interp_spline(grid.y, along_x.c, k=DEGREE, axis=1)
    progress.update(2, "fitted along y")
    knots = [along_x.t.tolist(), along_y.t.tolist()]
    point = ca.MX.sym("xy", 2)
    # CasADi's B-spline takes the coefficients (nx, ny) with the last axis (y) running fastest.
    coefficients = ca.DM(along_y.c.ravel())
    height = ca.bspline(point, coefficients, knots, [DEGREE, DEGREE], 1, {})
    surface = ca.Function("bathymetry", [point], [height], ["xy"], ["z"], {"never_inline": True})
    progress.update(3, "spline built")
    progress.close()
    return surface


def _grid_height(grid: BathymetryGrid, x, y):
    surface = grid_surface(grid)
    if isinstance(x, (ca.SX, ca.MX)) or isinstance(y, (ca.SX, ca.MX)):
        x = ca.fmin(ca.fmax(x, grid.x[0]), grid.x[-1])
        y = ca.fmin(ca.fmax(y, grid.y[0]), grid.y[-1])
        return surface(ca.horzcat(x, y).T).T
    x, y = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(y, dtype=float))
    outside = ~grid.contains(x, y)
    if outside.any():
        k = np.unravel_index(np.argmax(outside), x.shape)
        raise OffGridError(
            f"seabed.grid: the point (x, y) = ({x[k]:g}, {y[k]:g}) m is off the bathymetry grid "
            f"of {grid.file} ({grid.extent()})"
        )
    values = np.asarray(surface(np.vstack([x.ravel(), y.ravel()]))).reshape(x.shape)
    return values[()] if values.ndim == 0 else values


def seabed_height(seabed, x, y):
    """Height of the seabed at ``(x, y)`` (m): hills above the flat level, plus a grid's elevation.

    ``z(x, y) = z_grid(x, y) + sum_k k_k exp(-((x - x0_k)/p_k)^2 - ((y - y0_k)/q_k)^2)``
    (eq. 40); without a grid the first term is 0 and the height is relative to the flat level.

    Parameters
    ----------
    seabed : Seabed or sequence of Hill
        The scene's ``[seabed]`` section, or hills (each with ``height``, ``x0``, ``y0``,
        ``width_x``, ``width_y``, m).
    x, y : array or casadi expression, m

    Returns
    -------
    array or casadi expression, m

    Raises
    ------
    OffGridError
        A numeric point off the grid (a symbolic one is held at the grid's edge).
    """
    hills, grid = _parts(seabed)
    symbolic = isinstance(x, (ca.SX, ca.MX)) or isinstance(y, (ca.SX, ca.MX))
    exp = ca.exp if symbolic else np.exp
    total = 0.0 * x
    for hill in hills:
        total = total + hill.height * exp(
            -(((x - hill.x0) / hill.width_x) ** 2) - ((y - hill.y0) / hill.width_y) ** 2
        )
    if grid is not None:
        total = total + _grid_height(grid, x, y)
    return total


def clearance_reference(seabed, start) -> float:
    """The reference ``r`` of ``e(t) = z_E(t) - z(x_E, y_E) - r`` (m).

    Relative seabed: ``r = z_E(0) - z(x_E(0), y_E(0))``, the end's start over the seabed's height
    under it. Absolute seabed (a grid): ``r = delta`` (``seabed.clearance``), the target.

    Parameters
    ----------
    seabed : Seabed or sequence of Hill
    start : array (3,) or longer (a state: its first three entries), m
        The end's starting position.
    """
    if getattr(seabed, "absolute", False):
        return float(seabed.clearance)
    return float(start[2] - seabed_height(seabed, start[0], start[1]))


def clearance_error(seabed, end_positions: np.ndarray) -> np.ndarray:
    """Deviation of the end from the clearance ``delta`` over the seabed, ``e(t)`` (eq. 39), m.

    ``e = z_E(t) - z(x_E(t), y_E(t)) - r`` with ``r`` of :func:`clearance_reference` taken at the
    first position: the end should stay ``delta`` above the seabed, which may rise under it.

    Parameters
    ----------
    seabed : Seabed or sequence of Hill
    end_positions : array (k, 3), m
    """
    x, y, z = end_positions.T
    return z - seabed_height(seabed, x, y) - clearance_reference(seabed, end_positions[0])


def seabed_elevation(seabed, x, y, reference):
    """The seabed's elevation ``z_sb(x, y)`` (m, up from the sea surface), numeric or symbolic.

    Absolute seabed: the grid plus the hills. Relative seabed: the hills on the flat level
    ``r - delta`` that the end's start fixes.

    Parameters
    ----------
    seabed : Seabed
    x, y : array or casadi expression, m
    reference : float or casadi expression, m
        ``r`` of :func:`clearance_reference` at the run's start.
    """
    return seabed_height(seabed, x, y) + reference - seabed.clearance


def clearance(seabed, end, reference):
    """Height of the end above the seabed, ``z_E - z_sb(x_E, y_E) = delta + e`` (m).

    Parameters
    ----------
    seabed : Seabed
        The scene's ``[seabed]`` section (its ``clearance`` is delta).
    end : array (k, 3) or (3,), or a casadi column whose first three entries are x_E, y_E, z_E
        The end's positions, m.
    reference : float or casadi expression, m
        ``r`` of :func:`clearance_reference` at the run's start.

    Returns
    -------
    array (k,) or float, or casadi expression, m
    """
    if isinstance(end, (ca.SX, ca.MX)):
        x, y, z = end[0], end[1], end[2]
    else:
        x, y, z = np.moveaxis(np.asarray(end, dtype=float)[..., :3], -1, 0)
    return z - seabed_elevation(seabed, x, y, reference)


def clearance_margin(seabed, end, reference):
    """How far the end is above the minimum clearance: ``z_E - z_sb(x_E, y_E) - c_min`` (m).

    The hard constraint of ``seabed.minimum_clearance`` is ``clearance_margin >= 0`` at every
    sample; numeric or symbolic, like :func:`clearance`.

    Parameters
    ----------
    seabed : Seabed
        With ``minimum_clearance`` set.
    end, reference
        As for :func:`clearance`.

    Raises
    ------
    ValueError
        ``seabed.minimum_clearance`` is not set.
    """
    if seabed.minimum_clearance is None:
        raise ValueError("seabed.minimum_clearance is not set: the scene has no hard clearance")
    return clearance(seabed, end, reference) - seabed.minimum_clearance


def check_on_grid(seabed, end_positions: np.ndarray, time: np.ndarray) -> None:
    """Raise :class:`OffGridError` if the end leaves the grid (no-op without a grid).

    Parameters
    ----------
    seabed : Seabed or sequence of Hill
    end_positions : array (k, 3), m
    time : array (k,), s
    """
    grid = bathymetry(seabed)
    if grid is None:
        return
    x, y = end_positions[:, 0], end_positions[:, 1]
    outside = ~grid.contains(x, y)
    if outside.any():
        k = int(np.argmax(outside))
        raise OffGridError(
            f"seabed.grid: the end leaves the bathymetry grid of {grid.file} at t = "
            f"{time[k]:g} s, (x, y) = ({x[k]:g}, {y[k]:g}) m ({grid.extent()}); extend the grid"
        )


def check_start(seabed, start: np.ndarray) -> None:
    """Raise :class:`OffGridError` if the end starts off the grid or under an absolute seabed.

    Parameters
    ----------
    seabed : Seabed or sequence of Hill
    start : array (3,) or longer, m
        The end's starting position (the hanging equilibrium).
    """
    if not getattr(seabed, "absolute", False):
        return
    check_on_grid(seabed, np.asarray(start[:3], dtype=float)[None, :], np.zeros(1))
    height = float(start[2] - seabed_height(seabed, start[0], start[1]))
    if height < 0:
        raise OffGridError(
            f"seabed.grid: the end starts {-height:.3g} m under the seabed at (x, y, z) = "
            f"({start[0]:g}, {start[1]:g}, {start[2]:g}) m: the cable is longer than the water "
            "there is deep; shorten cable.length or move top.start"
        )


def seabed_findings(
    seabed, time: np.ndarray, end: np.ndarray
) -> tuple[str | None, list[str], bool]:
    """Where a run's end went under the seabed, or under ``seabed.minimum_clearance``.

    On an absolute seabed (a grid) the end under the seabed by more than
    :data:`PENETRATION_TOLERANCE` is a rope through the ground: the run fails (the model has no
    seabed contact). A relative seabed lies ``delta`` below the start by the scene's choice (it
    places the seabed in plots, and the objective does not see it): the end under it is a note,
    as is an end between the seabed and ``seabed.minimum_clearance``.

    Parameters
    ----------
    seabed : Seabed
    time : array (k,), s
    end : array (k, 3), m

    Returns
    -------
    failure : str or None
        When, where and how deep the end went under an absolute seabed.
    notes : list of str
    under : bool
        Whether the end went under the seabed (a failure or, relative, a note).
    """
    height = clearance(seabed, end, clearance_reference(seabed, end[0]))
    k = int(np.argmin(height))
    x, y, z = end[k]
    place = f"at t = {time[k]:g} s, (x, y, z) = ({x:.1f}, {y:.1f}, {z:.1f}) m"
    under = height < -PENETRATION_TOLERANCE
    failure, notes = None, []
    if under.any():
        text = (
            f"the end goes {-height[k]:.4g} m under the seabed {place} (under it from t = "
            f"{time[int(np.argmax(under))]:g} s, {np.count_nonzero(under)} of {time.size} samples)"
        )
        if getattr(seabed, "absolute", False):
            failure = text + ": the rope has no seabed contact, so the run is not physical there"
        else:
            notes.append(f"{text}; the seabed is relative (delta = {seabed.clearance:g} m "
                         "under the start)")  # fmt: skip
    minimum = getattr(seabed, "minimum_clearance", None)
    if minimum is not None and not under.any() and height[k] < minimum - PENETRATION_TOLERANCE:
        notes.append(
            f"the end comes within {height[k]:.4g} m of the seabed {place}, under "
            f"seabed.minimum_clearance = {minimum:g} m"
        )
    return failure, notes, bool(under.any())


def trapezoid_weights(step: float, count: int) -> np.ndarray:
    """Weights (s) of the trapezoidal rule on ``count`` points ``step`` (s) apart."""
    weights = np.full(count, step)
    weights[[0, -1]] = step / 2
    return weights


def rms_objective(time: np.ndarray, error: np.ndarray) -> float:
    """``Omega = sqrt(1/T int_0^T e^2 dt)`` (eq. 39) by the trapezoidal rule, m."""
    span = time[-1] - time[0]
    return float(np.sqrt(np.trapezoid(error**2, time) / span))
