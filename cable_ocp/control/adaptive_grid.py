"""An adaptive control grid: Hermite nodes where the winch needs them (issue 43, paper §6).

``GridSettings(adaptive=True)`` chooses the open loop's Hermite nodes among the default grid's
(:func:`cable_ocp.control.defaults.control_grid`, about 5 s apart, or ``adaptive_finest`` times
finer; every one of them on an RK4 step end of every model, so that any subset is too) by
coarsening, with the error measured in the objective itself (Betts' equidistribution, run from
the fine end):

1. The model correction's first solve and its full-model run are the uniform default's (the
   default grid, from the locked first guess): they give the reduced model's bias ``b``.
2. At that optimum the corrected clearance error is linearised in the default grid's parameters
   (the Gauss-Newton solver's last Jacobian; another solver's takes one sensitivity sweep):
   ``r = W (e + b)``, ``A = W J``, Omega^2 ~ ``|r + A d|^2``. Its QP step within the winch bounds
   (and the minimum clearance) is the corrected optimum on the default grid, predicted: ``p*``
   and Omega*.
3. Nodes go, cheapest first, while the model's Omega^2 of the profile that interpolates ``p*`` on
   the nodes left stays within ``((1 + adaptive_tolerance) Omega* + OMEGA_ROUND_OFF)^2``. A
   node's cost is the exact change of that quadratic when one cubic spans its two neighbours
   (through their angles and rates); a pass removes no two neighbours, and passes repeat until
   no node fits in what is left.
4. The model-correction solves that remain run on the nodes left, from ``p*`` on them (no solve
   of the coarse grid is re-solved on a finer one), and the verification is the usual one.

Why from the fine end: a solve's cost hardly depends on its parameters (the sensitivity sweep's
cost is the model's Jacobians at every RK4 stage; 2-3 iterations of a 23-interval grid took as
long as of a 90-interval one on whole-space seed 1 case 2), so refinement rounds from a coarse
grid each cost about a default solve, and the coarse grid's model error (before any correction)
misled them. Coarsening costs no solve beyond the uniform default's. The winch bounds and the
minimum clearance are rows at every RK4 point of every grid, so no constraint is lost between
coarse nodes (the verification checks the full model at its own steps). CONVENTIONS.md §5 states
the rule and its measurements.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from cable_ocp.control.gauss_newton import GaussNewton, GaussNewtonSettings
from cable_ocp.control.hermite_nodes import HermiteNodes
from cable_ocp.control.problem import WinchProblem
from cable_ocp.drive.bounds import LinearBounds
from cable_ocp.drive.controls import hermite_polynomials

# m: an Omega within this of the prediction is within the tolerance, however small both are
# (a straight profile that a coarse grid fits to round-off). 0.1 um was 6 % of whole-space seed
# 1 case 3's 1.8 um, and its adaptive Omega came out 4.3 % above the uniform one's.
OMEGA_ROUND_OFF = 1e-9


def with_nodes(problem: WinchProblem, times: np.ndarray) -> WinchProblem:
    """The problem with a Hermite control on the node times ``times`` (s), its bounds rebuilt."""
    control = HermiteNodes(np.asarray(times, dtype=float))
    bounds = LinearBounds.build(problem.scene, control, problem.grid)
    return replace(problem, control=control, bounds=bounds)


def on_nodes(control, parameters: np.ndarray, times: np.ndarray) -> np.ndarray:
    """Hermite parameters on the nodes ``times`` (s) of the angle of ``control``: values, rates.

    Exact for a control whose nodes are among ``times`` (a cubic is its own Hermite
    interpolant); node 0 (held at rest) is left out.
    """
    b0, b1, _ = control.basis(np.asarray(times, dtype=float)[1:])
    return np.concatenate([b0 @ parameters, b1 @ parameters])


@dataclass(frozen=True, eq=False)
class Coarsening:
    """The nodes chosen among the default grid's, and where their solves start.

    Attributes
    ----------
    problem : WinchProblem
        The problem on the chosen nodes.
    parameters : array
        The default grid's predicted corrected optimum ``p*`` on them (rad, rad/s).
    intervals : int
        Intervals of the default grid.
    predicted : float, m
        Omega* on the default grid, predicted (Gauss-Newton, corrected model).
    omega : float, m
        The model's Omega of ``p*`` interpolated on the chosen nodes (before their solves).
    """

    problem: WinchProblem
    parameters: np.ndarray
    intervals: int
    predicted: float
    omega: float

    def describe(self) -> str:
        """One phrase: the grids and their predicted Omega."""
        return (
            f"adaptive grid of {self.problem.control.intervals} of the default grid's "
            f"{self.intervals} intervals (predicted Omega on the corrected model "
            f"{self.omega:.3g} m against the default grid's {self.predicted:.3g} m)"
        )


class Quadratic:
    """The Gauss-Newton model ``|r + A d|^2`` of Omega^2 (m^2) about a default-grid profile.

    Parameters
    ----------
    residual : array (K + 1,), m
        ``W (e + b)``: Omega^2 at ``profile`` is its square norm.
    jacobian : array (K + 1, 2 N), m/rad
        ``W J`` in the default grid's parameters ``[phi_1..phi_N, phi'_1..phi'_N]``.
    profile : array (2 N,)
        The profile on the default grid's nodes (rad, rad/s).
    """

    def __init__(self, residual: np.ndarray, jacobian: np.ndarray, profile: np.ndarray):
        self.objective = float(residual @ residual)
        self.gradient = jacobian.T @ residual
        self.hessian = jacobian.T @ jacobian
        self.count = jacobian.shape[1] // 2
        self.profile = np.array(profile, dtype=float)

    def moved(self, step: np.ndarray) -> None:
        """Centre the model at ``profile + step`` (exact: the model is quadratic)."""
        self.objective += float(2 * self.gradient @ step + step @ self.hessian @ step)
        self.gradient = self.gradient + self.hessian @ step
        self.profile = self.profile + step

    def columns(self, nodes: np.ndarray) -> np.ndarray:
        """The angle and rate columns of the default grid's nodes ``nodes`` (1 .. N)."""
        return np.r_[nodes - 1, self.count + nodes - 1]

    def spanned(self, left: int, right: int, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The columns inside ``left..right`` and their values when one cubic spans them.

        The cubic runs through the angles and rates of :attr:`profile` at the default nodes
        ``left`` and ``right`` (``times``: the default nodes, s).
        """
        angles = np.r_[0.0, self.profile[: self.count]]
        rates = np.r_[0.0, self.profile[self.count :]]
        inside = np.arange(left + 1, right)
        width = times[right] - times[left]
        h00, h10, h01, h11 = hermite_polynomials((times[inside] - times[left]) / width)
        ends = (angles[left], width * rates[left], angles[right], width * rates[right])
        value = sum(h[0] * e for h, e in zip((h00, h10, h01, h11), ends, strict=True))
        slope = sum(h[1] * e for h, e in zip((h00, h10, h01, h11), ends, strict=True)) / width
        return self.columns(inside), np.r_[value, slope]

    def coarsest(
        self, times: np.ndarray, allowed: float, bounds: LinearBounds | None = None
    ) -> tuple[np.ndarray, float]:
        """The default nodes kept (indices into ``times``, s) and the model's Omega^2 (m^2) then.

        The Omega^2 stays within ``allowed`` (m^2) where the model's at :attr:`profile` is.
        Greedy passes (module docstring, 3): each removes the nodes whose exact cost at the
        current profile fits in what is left, cheapest first, none beside one removed in the
        same pass. With ``bounds`` (the default grid's winch bounds), a node whose spanning
        cubic would break them stays: a winch that rides its bound cannot cut across it, and
        the model (blind to the bounds) would count that as a gain.
        """
        rows = None if bounds is None else [np.flatnonzero(c) for c in (bounds.matrix != 0).T]
        kept = list(range(times.size))
        current = self.profile.copy()
        slope = self.gradient.copy()  # the gradient of the model at ``current``, halved
        cost = self.objective
        while len(kept) > 2:
            costs = []
            for j in range(1, len(kept) - 1):
                columns, values = self.spanned(kept[j - 1], kept[j + 1], times)
                change = values - current[columns]
                if rows is not None and _breaks(bounds, rows, columns, current, change):
                    continue
                rise = change @ self.hessian[np.ix_(columns, columns)] @ change
                costs.append((rise + 2 * change @ slope[columns], j, columns, change))
            touched, removed = set(), []
            for rise, j, columns, change in sorted(costs, key=lambda c: c[0]):
                if cost + rise > allowed:
                    break
                if j - 1 in touched or j + 1 in touched:
                    continue
                touched.add(j)
                removed.append(kept[j])
                current[columns] += change
                slope += self.hessian[:, columns] @ change
                cost += rise
            if not removed:
                break
            kept = [k for k in kept if k not in set(removed)]
        return np.array(kept, dtype=int), cost


def _breaks(bounds: LinearBounds, rows: list, columns, current, change) -> bool:
    """Whether ``current`` moved by ``change`` in ``columns`` breaks a bound row they touch.

    ``rows``: the bound rows that each parameter enters.
    """
    touched = np.unique(np.concatenate([rows[c] for c in columns]))
    moved = current.copy()
    moved[columns] += change
    values = bounds.matrix[touched] @ moved
    return bool(np.any(values < bounds.lower[touched]) or np.any(values > bounds.upper[touched]))


def coarsen(
    problem: WinchProblem, solver, values, parameters: np.ndarray, tolerance: float
) -> Coarsening:
    """The nodes of ``problem``'s default grid to keep, at its corrected optimum (docstring).

    Parameters
    ----------
    problem : WinchProblem
        The problem on the default grid (a uniform Hermite control).
    solver : ProblemSolver
        Its solver, which solved it last at ``parameters``: a Gauss-Newton solver's last
        linearisation is taken again; another solver's problem is linearised anew.
    values : ProblemParameters
        The problem's named parameters with the model correction's bias.
    parameters : array
        The first solve's optimum on the default grid (rad, rad/s).
    tolerance : float
        ``GridSettings.adaptive_tolerance``.
    """
    model = solver
    if not isinstance(model, GaussNewton):
        model = GaussNewton(problem, GaussNewtonSettings())
    linearised = model.linearised_at(values, parameters)
    quadratic = Quadratic(
        model.weights * linearised.error, model.weights[:, None] * linearised.jacobian, parameters
    )
    bounds = problem.bounds
    step, _, _ = model.step(linearised, parameters, bounds.lower, bounds.upper, {})
    if step is not None:
        quadratic.moved(step)
    predicted = float(np.sqrt(max(quadratic.objective, 0.0)))
    times = problem.control.breakpoints
    allowed = ((1 + tolerance) * predicted + OMEGA_ROUND_OFF) ** 2
    kept, objective = quadratic.coarsest(times, allowed, bounds)
    chosen = with_nodes(problem, times[kept])
    return Coarsening(
        chosen,
        on_nodes(problem.control, quadratic.profile, times[kept]),
        problem.control.intervals,
        predicted,
        float(np.sqrt(max(objective, 0.0))),
    )
