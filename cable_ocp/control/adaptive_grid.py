"""An adaptive control grid: Hermite nodes where the winch needs them (issue 43, paper §6).

``GridSettings(adaptive=True)`` chooses the open loop's Hermite nodes among the default grid's
(:func:`cable_ocp.control.defaults.control_grid`, about 5 s apart; every one of them on an RK4
step end of every model, so that any subset is too) by refinement, as hp-adaptive direct
transcription does (GPOPS-II's error per mesh interval, Betts' equidistribution), with the error
measured in the objective itself:

The default grid here is the shooting grid: about 5 s, or ``adaptive_finest`` times finer.

1. Start coarse: every ``adaptive_start * adaptive_finest``-th node of the default grid (20 s
   apart by default).
2. Solve on the reduced model (the solver of the settings), warm-started from the last profile
   (its angle and rate at the new nodes: exact where intervals were split).
3. Linearise the clearance error at that optimum in the default grid's parameters (one
   sensitivity sweep of the default grid's Gauss-Newton solver): residual ``r = W e`` and
   ``A = W J`` with Omega^2 = ``|r|^2``. The Gauss-Newton decrease of Omega^2 from freeing a set
   ``S`` of the default grid's parameters is ``g_S^T (A_S^T A_S)^-1 g_S``, ``g = A^T r``:

   - the prediction: Omega on the default grid, from the decrease of its QP within the winch
     bounds (and the minimum clearance), so that a winch that rides its bounds is not promised
     what no grid can give;
   - an interval's *split gain*: the decrease from freeing the default nodes inside it, those in
     an active bound row left out (no gain where the winch rides a bound);
   - a node's *merge cost*: the rise ``d^T A^T A d + 2 g^T d`` when one cubic spans its two
     neighbours (``d`` the change of the default grid's parameters), without re-solving.

4. Stop when Omega is within ``adaptive_tolerance`` of the prediction (and
   :data:`OMEGA_ROUND_OFF`), after removing the nodes whose merge costs fit in what is left of
   the tolerance (cheapest first, never two in a row; the caller's solve re-optimises on what
   remains). After ``adaptive_rounds`` solves not within it, end on the whole default grid
   (solved from the last optimum: Omega as the default grid's, at its cost). Otherwise split
   each interval whose gain is above its share of the allowed excess of Omega^2
   (``((1 + tol)^2 - 1)`` times the predicted one, over the intervals) and above
   1/:data:`EXCESS_SHARES` of its share of the excess left (the largest gain at least): at every
   default node inside it when its gain is above :data:`FULL_SPLIT` times that, at the one
   nearest its middle otherwise. Nodes whose merge cost is under :data:`MERGE_SHARE` of that
   threshold (not beside a split) go. Then go to 2.

The last solve's optimum and its solver start :func:`cable_ocp.control.optimization.solve_verified`
on the chosen grid (model correction and verification as on any grid). The winch bounds and the
minimum clearance are rows at every RK4 point of every grid, so no constraint is lost between
coarse nodes (the verification checks the full model at its own steps). CONVENTIONS.md §5 states
the rule and its measurements.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np

from cable_ocp.control.gauss_newton import DAMPING, GaussNewton, GaussNewtonSettings
from cable_ocp.control.hermite_nodes import HermiteNodes
from cable_ocp.control.problem import WinchProblem
from cable_ocp.drive.bounds import LinearBounds
from cable_ocp.drive.controls import hermite_polynomials

# A node is removed when its merge cost is under this share of an interval's share of the
# allowed excess of Omega^2.
MERGE_SHARE = 0.1
# m: an Omega within this of the prediction is within the tolerance, however small both are
# (a straight profile that the coarse grid fits to round-off).
OMEGA_ROUND_OFF = 1e-7
# A winch bound row within this of its limit (rad, rad/s, rad/s^2, m) is active.
ACTIVE = 1e-3
# A grid far off splits the intervals that carry more than 1/EXCESS_SHARES of their share of
# the excess of Omega^2 over the prediction.
EXCESS_SHARES = 8.0
# An interval whose split gain is above this many shares takes all the default nodes inside it.
FULL_SPLIT = 8.0


@dataclass(frozen=True)
class Round:
    """One solve of the refinement.

    Attributes
    ----------
    intervals : int
        Intervals of its grid.
    omega : float, m
        Omega on the optimisation model at its optimum.
    predicted : float, m
        Omega on the default grid as predicted from its optimum (NaN where none was).
    """

    intervals: int
    omega: float
    predicted: float = float("nan")


@dataclass(frozen=True, eq=False)
class Refinement:
    """What the refinement chose, and the solver and optimum on its last grid.

    Attributes
    ----------
    problem : WinchProblem
        The problem on the chosen nodes.
    solver : ProblemSolver
        Its solver, built (the last round's).
    parameters : array
        The profile on its nodes to start from (rad, rad/s): the last solve's optimum, on the
        nodes that remain after the last merges.
    rounds : list of Round
    build_time, solve_time : float, s
        Building and solving in the rounds before the last.
    iterations : int
        Solver iterations in the rounds before the last.
    """

    problem: WinchProblem
    solver: object
    parameters: np.ndarray
    rounds: list[Round]
    build_time: float
    solve_time: float
    iterations: int

    def describe(self) -> str:
        """One phrase: the grids, their Omega and the prediction."""
        counts = [r.intervals for r in self.rounds]
        final = self.problem.control.intervals
        grids = " -> ".join(map(str, counts + ([final] if final != counts[-1] else [])))
        omegas = ", ".join(f"{r.omega:.3g}" for r in self.rounds)
        predicted = [r.predicted for r in self.rounds if np.isfinite(r.predicted)]
        told = f"; the default grid's predicted {predicted[-1]:.3g} m" if predicted else ""
        return f"adaptive grid of {grids} intervals (Omega on the model {omegas} m{told})"


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


def refine(problem: WinchProblem, build, values, guess: np.ndarray, grid) -> Refinement:
    """Choose the Hermite nodes of ``problem`` among its control's (module docstring).

    Parameters
    ----------
    problem : WinchProblem
        The problem on the default grid (a uniform Hermite control).
    build : callable
        ``problem -> solver`` (a build of :data:`cable_ocp.control.solvers.SOLVERS`, quiet).
    values : ProblemParameters
        The problem's named parameters.
    guess : array
        The first guess on the default grid (rad, rad/s).
    grid : GridSettings
        Its ``adaptive_start``, ``adaptive_tolerance`` and ``adaptive_rounds``.

    Returns
    -------
    Refinement
        Its times count every round's solve and indicators, and the builds before the last.
    """
    base = problem.control.breakpoints
    count = base.size - 1
    start = grid.adaptive_start * grid.adaptive_finest
    chosen = np.unique(np.r_[np.arange(0, count + 1, start), count])
    # The default grid's Gauss-Newton model: its linearisation and its QP (the bounds).
    model = GaussNewton(problem, GaussNewtonSettings())
    rounds: list[Round] = []
    build_time = solve_time = 0.0
    iterations = 0
    control, parameters = problem.control, guess
    nothing = np.zeros(0, dtype=int)
    while True:
        trial = with_nodes(problem, base[chosen])
        solver = build(trial)
        outcome = solver.solve(values, on_nodes(control, parameters, base[chosen]))
        control, parameters = trial.control, outcome.parameters
        solve_time += outcome.solve_time
        iterations += outcome.iterations
        done, split, merged = Round(control.intervals, outcome.omega), nothing, nothing
        if outcome.success:
            started = time.perf_counter()
            on_base = on_nodes(control, parameters, base)
            linearised = model.linearisation(values, on_base)
            if linearised.finite:
                indicators = Indicators.at(model, linearised, on_base)
                predicted, split, merged = indicators.decide(chosen, grid.adaptive_tolerance, base)
                if split.size and len(rounds) + 1 >= grid.adaptive_rounds:
                    # Out of solves and not within the tolerance: the whole default grid.
                    split, merged = np.setdiff1d(np.arange(count + 1), chosen), nothing
                done = Round(control.intervals, outcome.omega, predicted)
            solve_time += time.perf_counter() - started
        rounds.append(done)
        if not split.size and not merged.size:
            return Refinement(trial, solver, parameters, rounds, build_time, solve_time, iterations)
        build_time += solver.build_time
        chosen = np.union1d(np.setdiff1d(chosen, merged), split)
        if not split.size or len(rounds) >= grid.adaptive_rounds:
            # Within the tolerance (nodes merged), or out of solves (the whole default grid):
            # the caller solves on it from this optimum.
            return _on(problem, base, chosen, control, parameters, build, rounds, build_time,
                       solve_time, iterations)  # fmt: skip


def _on(problem, base, chosen, control, parameters, build, *figures) -> Refinement:
    """The refinement that ends on the default nodes ``chosen``, unsolved, from ``parameters``.

    ``figures``: the rounds, build time, solve time and iterations so far.
    """
    trial = with_nodes(problem, base[chosen])
    return Refinement(trial, build(trial), on_nodes(control, parameters, base[chosen]), *figures)


class Indicators:
    """The Gauss-Newton model of Omega^2 in the default grid's parameters, at one optimum.

    Parameters
    ----------
    residual : array (K + 1,), m
        ``W e``: Omega^2 is its square norm.
    jacobian : array (K + 1, 2 N), m/rad
        ``W J`` in the default grid's parameters ``[phi_1..phi_N, phi'_1..phi'_N]``.
    profile : array (2 N,)
        The optimum on the default grid's nodes (rad, rad/s).
    decrease : float or None, m^2
        The decrease of Omega^2 that the default grid's QP predicts within the winch bounds (and
        the minimum clearance): the prediction; None: the unbounded one.
    pinned : array of bool (2 N,) or None
        The parameters in a winch bound row that is active at ``profile``: a winch that rides
        its bound gains nothing from more nodes there, so they count in no split gain.
    """

    def __init__(self, residual, jacobian, profile, decrease=None, pinned=None):
        self.objective = float(residual @ residual)
        self.gradient = jacobian.T @ residual
        self.hessian = jacobian.T @ jacobian
        self.count = jacobian.shape[1] // 2
        self.damping = DAMPING * max(float(np.max(np.diag(self.hessian))), 1e-30)
        self.profile = profile
        self.decrease = decrease
        self.free = ~pinned if pinned is not None else np.ones(2 * self.count, dtype=bool)

    @classmethod
    def at(cls, model: GaussNewton, linearised, profile: np.ndarray) -> Indicators:
        """The indicators of the default grid's solver ``model`` at its linearisation."""
        bounds = model.problem.bounds
        _, decrease, status = model.step(linearised, profile, bounds.lower, bounds.upper, {})
        values = bounds.matrix @ profile
        active = (values - bounds.lower < ACTIVE) | (bounds.upper - values < ACTIVE)
        pinned = np.any(bounds.matrix[active] != 0.0, axis=0)
        return cls(
            model.weights * linearised.error,
            model.weights[:, None] * linearised.jacobian,
            profile,
            decrease if status == "solved" else None,
            pinned,
        )

    def gain(self, columns: np.ndarray) -> float:
        """The decrease of Omega^2 (m^2) from freeing the parameters ``columns`` (not pinned)."""
        columns = columns[self.free[columns]]
        if columns.size == 0:
            return 0.0
        block = self.hessian[np.ix_(columns, columns)] + self.damping * np.eye(columns.size)
        g = self.gradient[columns]
        return float(g @ np.linalg.solve(block, g))

    def columns(self, nodes: np.ndarray) -> np.ndarray:
        """The angle and rate columns of the default grid's nodes ``nodes`` (1 .. N)."""
        return np.r_[nodes - 1, self.count + nodes - 1]

    def predicted(self) -> float:
        """Omega (m) on the default grid, predicted (within the bounds where the QP solved)."""
        decrease = self.decrease
        if decrease is None:
            decrease = self.gain(np.arange(2 * self.count))
        return float(np.sqrt(max(self.objective - decrease, 0.0)))

    def merge_cost(self, left: int, right: int, times: np.ndarray) -> float:
        """The rise of Omega^2 (m^2) when one cubic spans the default nodes ``left..right``.

        ``times``: the default nodes (s).
        """
        angles = np.r_[0.0, self.profile[: self.count]]
        rates = np.r_[0.0, self.profile[self.count :]]
        inside = np.arange(left + 1, right)
        width = times[right] - times[left]
        h00, h10, h01, h11 = hermite_polynomials((times[inside] - times[left]) / width)
        ends = (angles[left], width * rates[left], angles[right], width * rates[right])
        value = sum(h[0] * e for h, e in zip((h00, h10, h01, h11), ends, strict=True))
        slope = sum(h[1] * e for h, e in zip((h00, h10, h01, h11), ends, strict=True)) / width
        change = np.zeros(2 * self.count)
        change[self.columns(inside)] = np.r_[value - angles[inside], slope - rates[inside]]
        return float(change @ self.hessian @ change + 2 * self.gradient @ change)

    def decide(self, chosen: np.ndarray, tolerance: float, times: np.ndarray):
        """The prediction (m), the default nodes to add and those to remove (none: stop).

        ``chosen``: the grid's nodes (indices of the default nodes ``times``, s).
        """
        predicted = self.predicted()
        nothing = np.zeros(0, dtype=int)
        allowed = ((1 + tolerance) * predicted + OMEGA_ROUND_OFF) ** 2
        if self.objective <= allowed:
            return predicted, nothing, self._spare(chosen, times, allowed)
        share = ((1 + tolerance) ** 2 - 1) * predicted**2 / (chosen.size - 1)
        pairs = list(zip(chosen[:-1], chosen[1:], strict=True))
        inside = [self.columns(np.arange(a + 1, b)) for a, b in pairs]
        gains = np.array([self.gain(c) for c in inside])
        # Split where an interval carries more than its share of the allowed excess, and more
        # than an eighth of its share of the excess left now (so that a grid far off refines
        # where it is furthest off first).
        threshold = max(share, (self.objective - predicted**2) / (EXCESS_SHARES * gains.size))
        splitting = gains > threshold
        splitting[np.argmax(gains)] |= gains.max() > 0
        splitting &= np.diff(chosen) > 1
        if not splitting.any():
            return predicted, nothing, nothing
        merged = []
        for i in range(1, chosen.size - 1):
            if splitting[i - 1] or splitting[i] or (merged and merged[-1] == chosen[i - 1]):
                continue
            cost = self.merge_cost(chosen[i - 1], chosen[i + 1], times)
            if cost < MERGE_SHARE * threshold:
                merged.append(chosen[i])
        # An interval that carries more than FULL_SPLIT shares takes every default node inside
        # it at once; the others are halved.
        split = [
            np.arange(a + 1, b) if gain > FULL_SPLIT * threshold else [(a + b) // 2]
            for (a, b), gain, chosen_one in zip(pairs, gains, splitting, strict=True)
            if chosen_one
        ]
        return predicted, np.concatenate(split).astype(int), np.array(merged, dtype=int)

    def _spare(self, chosen: np.ndarray, times: np.ndarray, allowed: float) -> np.ndarray:
        """Nodes to remove from a grid within the tolerance, cheapest first, none two in a row.

        Their merge costs add up to at most what is left of ``allowed`` Omega^2 (m^2).
        """
        costs = [
            (self.merge_cost(chosen[i - 1], chosen[i + 1], times), i)
            for i in range(1, chosen.size - 1)
        ]
        left, taken = allowed - self.objective, set()
        for cost, i in sorted(costs):
            if cost > left:
                break
            if i - 1 in taken or i + 1 in taken:
                continue
            taken.add(i)
            left -= max(cost, 0.0)
        return np.sort(chosen[list(taken)]).astype(int)
