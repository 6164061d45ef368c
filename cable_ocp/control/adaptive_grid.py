"""An adaptive control grid: Hermite nodes where the winch needs them (issue 43, paper §6).

``GridSettings(adaptive=True)`` chooses the open loop's Hermite nodes among candidates: the nodes
of a grid ``adaptive_finest`` (2 by default) times finer than the default one
(:func:`cable_ocp.control.defaults.control_grid`, about 5 s apart), each default interval split
where the scene's steps allow, the default grid's own nodes otherwise
(:func:`cable_ocp.control.defaults.candidate_split`); every candidate is on an RK4 step end of
the scene's model and of the candidates' optimisation model, so that any subset is too. It
coarsens, with the error measured in the objective itself (Betts' equidistribution, run from the
fine end):

1. The first solve is the uniform default grid's own (its problem, model step and bound rows),
   on the optimisation model as it is: it gives its optimum ``p0``, and no full-model run yet.
2. At ``p0`` the clearance error is linearised in the default grid's parameters (the
   Gauss-Newton solver's last Jacobian; another solver's takes one sensitivity sweep):
   ``r = W e``, ``A = W J``, Omega^2 ~ ``|r + A d|^2``. Its QP step within the winch bounds
   (and the minimum clearance; the step the solve ended on, :meth:`GaussNewton.final_step`,
   where it ended on one) predicts the default grid's optimum, Omega*. With finer
   candidates, their problem is built then (its model step derived from their interval,
   :func:`cable_ocp.control.shooting.candidate_settings`: a shorter one where the default step
   does not split), the same model is taken once more in their parameters and moved to its
   QP's optimum: on the default grid's step, the first solve's last sweep carried onto them
   (:meth:`ErrorLinearisation.carried`: its stage Jacobians through their map, the same
   model as the default grid's Jacobian); on a shorter step, one sweep at ``p0``.
3. Nodes go, cheapest first, while the model's Omega^2 of the profile that interpolates the
   optimum on the nodes left stays within ``((1 + adaptive_tolerance) Omega* +
   OMEGA_ROUND_OFF)^2``. A node's cost is the exact change of that quadratic when one cubic
   spans its two neighbours (through their angles and rates); a cubic that would break a winch
   bound row keeps its node; a pass removes no two neighbours, and passes repeat until no node
   fits in what is left. The model is then re-optimised on the nodes kept (its QP within their
   bounds) and coarsened again, up to :data:`REOPTIMISED` times.
4. The model correction then runs on the nodes kept, as it would on the default grid: its
   first solve from the model's optimum on them, its full-model runs at a step that fits them
   (:func:`cable_ocp.control.verification.fitted_step`), the verification the usual one. That
   first solve starts with the default grid's Jacobian carried onto the nodes (no sensitivity
   sweep) when one run confirms the error it predicts (:meth:`GaussNewton.start_from`). The
   default grid's profile is never run on the full model: the runs are the nodes' own, as many
   as the uniform grid's, and a correction solve that lowers its model's Omega^2 by less than
   :data:`cable_ocp.control.optimization.UNMOVED` from the best verified profile is not run,
   as on the uniform grid. If a solve on the nodes fails before one of their profiles verified
   (among the default grid's nodes, whole-space seed 1 case 10 blew the reduced model up at the
   model's optimum on 14 intervals), or none of their profiles verifies, the default grid goes
   on from ``p0`` as it would have alone, and the notes say so.

Why from the fine end: a solve's cost hardly depends on its parameters (a sensitivity sweep of
paper_hill's reduced model took 0.126 s on 22 parameters, 0.142 s on 84, 0.206 s on 168: the
model's Jacobians at every RK4 stage dominate it), so refinement rounds from a coarse grid each
cost about a default solve, and a coarse grid's optimum misled them where it was far from the
fine one's; coarsening needs only the fine optimum that the first solve gives. The winch bounds
and the minimum clearance are rows at every RK4 point of every grid, so no constraint is lost
between coarse nodes (the verification checks the full model at its own steps).
CONVENTIONS.md §5 states the rule and its measurements.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np
from scipy import sparse

from cable_ocp.control.gauss_newton import GaussNewton, GaussNewtonSettings
from cable_ocp.control.hermite_nodes import HermiteNodes
from cable_ocp.control.linearisation import Linearised
from cable_ocp.control.parameters import ProblemParameters
from cable_ocp.control.problem import WinchProblem
from cable_ocp.drive.bounds import LinearBounds
from cable_ocp.drive.controls import hermite_polynomials

# m: an Omega within this of the prediction is within the tolerance, however small both are
# (a straight profile that a coarse grid fits to round-off). 0.1 um was 6 % of whole-space seed
# 1 case 3's 1.8 um, and its adaptive Omega came out 4.3 % above the uniform one's.
OMEGA_ROUND_OFF = 1e-9
# Times the model is re-optimised on the nodes kept and coarsened again (once: 150 -> 132
# parameters on whole-space seed 1 case 9, a third pass 130 for 0.7 s more; 0-2 fewer on others).
REOPTIMISED = 1
# Finer candidates are left out where the default grid's predicted Omega* is more than this
# times the model's optimum without the winch bounds: the winch's reach limits Omega there, and
# the finer grid's bound rows only cost time (whole-space seed 0 case 11, Omega 62 m: 2.8 s and
# 166 parameters on the default grid, 12.1 s and 254 with candidates twice as fine).
REACH_LIMITED = 1.5


def with_nodes(problem: WinchProblem, times: np.ndarray) -> tuple[WinchProblem, np.ndarray]:
    """The problem with a Hermite control on the node times ``times`` (s), among its own nodes.

    Returns the problem and the embedding (``problem``'s parameters of each parameter of the
    new control, :func:`on_nodes`). The embedding maps ``problem``'s bound rows onto the new
    control: on the same RK4 sub-intervals, each cubic is the other's, so the rows are the same
    constraints (the heave's extremes are not sampled again).
    """
    control = HermiteNodes(np.asarray(times, dtype=float))
    embedding = on_nodes(control, np.eye(control.size), problem.control.breakpoints)
    # Each row holds one sub-interval's cubic: a few nonzeros (0.1 s dense on 240 parameters).
    bounds = replace(problem.bounds, matrix=problem.bounds.sparse_matrix @ embedding)
    return replace(problem, control=control, bounds=bounds), embedding


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
        The default grid's predicted optimum ``p*`` on them (rad, rad/s).
    intervals : int
        Intervals of the default grid.
    predicted : float, m
        Omega* on the default grid, predicted (Gauss-Newton, the optimisation model).
    omega : float, m
        The model's Omega of ``p*`` interpolated on the chosen nodes (before their solves).
    candidates : array, s
        The nodes they were chosen among.
    linearised : Linearised
        The error at ``parameters`` and its Jacobian in their parameters, predicted
        from the default grid's linearisation (the first solve on the nodes starts from it when
        a run confirms the error: :meth:`GaussNewton.start_from`).
    values : ProblemParameters
        The named parameters of :attr:`problem`: the first problem's, or the candidates' own
        where their model step is shorter.
    default_step : float, s
        The first problem's model step.
    """

    problem: WinchProblem
    parameters: np.ndarray
    intervals: int
    predicted: float
    omega: float
    candidates: np.ndarray
    linearised: Linearised
    values: ProblemParameters
    default_step: float

    def describe(self) -> str:
        """One phrase (no "; ", which separates a result's notes): the grids and their Omega."""
        among = self.candidates.size - 1
        finer = f" among {among} candidates" if among != self.intervals else ""
        if self.problem.step != self.default_step:
            finer += f" at h = {self.problem.step:.4g} s"
        return (
            f"adaptive grid of {self.problem.control.intervals} intervals{finer} (the default "
            f"grid's {self.intervals}: predicted Omega on the optimisation model {self.omega:.3g} "
            f"m against its {self.predicted:.3g} m)"
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

    def unbounded(self) -> float:
        """Omega (m) of the model's optimum without the winch bounds (wherever it is centred)."""
        step = np.linalg.lstsq(self.hessian, -self.gradient, rcond=None)[0]
        return float(np.sqrt(max(self.objective + self.gradient @ step, 0.0)))

    def coarsest(
        self,
        times: np.ndarray,
        allowed: float,
        bounds: LinearBounds | None = None,
        kept: np.ndarray | None = None,
    ) -> np.ndarray:
        """The nodes kept (indices into ``times``, s), among ``kept`` (None: all).

        The model's Omega^2 stays within ``allowed`` (m^2) where it is at :attr:`profile`, which
        should lie on the nodes ``kept``. Greedy passes (module docstring, 3): each removes the
        nodes whose exact cost at the current profile fits in what is left, cheapest first,
        none beside one removed in the same pass. With ``bounds`` (the candidate grid's winch
        bounds), a node whose spanning cubic would break them stays: a winch that rides its
        bound cannot cut across it, and the model (blind to the bounds) would count that as a
        gain. The model is then centred at the profile on the nodes kept.
        """
        kept = list(range(times.size)) if kept is None else list(kept)
        current = self.profile.copy()
        slope = self.gradient.copy()  # the gradient of the model at ``current``, halved
        cost = self.objective
        spans = _Spans(self, times, current, bounds)
        while len(kept) > 2:
            costs = []
            ends = [(kept[j - 1], kept[j + 1]) for j in range(1, len(kept) - 1)]
            for j, span in enumerate(spans.made(ends), start=1):
                if span.breaks(spans.rows_at, bounds):
                    continue
                costs.append((span.rise + 2 * span.change @ slope[span.columns], j, span))
            touched, removed = set(), []
            for rise, j, span in sorted(costs, key=lambda c: c[0]):
                if cost + rise > allowed:
                    break
                if j - 1 in touched or j + 1 in touched:
                    continue
                # Its cost at the profile as the pass has moved it so far (the model couples
                # spans: deep_lift's 2000 m elastic line had reached 6.5 times the allowed
                # Omega on costs taken at the pass's start).
                rise = span.rise + 2 * span.change @ slope[span.columns]
                if cost + rise > allowed:
                    continue
                touched.add(j)
                removed.append(kept[j])
                slope += self.hessian[:, span.columns] @ span.change
                spans.moved(span)
                cost += rise
            if not removed:
                break
            kept = [k for k in kept if k not in set(removed)]
        self.moved(current - self.profile)
        return np.array(kept, dtype=int)


@dataclass(frozen=True, eq=False)
class _Span:
    """One cubic across the nodes between two kept ones, as the greedy passes cost it.

    Attributes
    ----------
    columns : array
        The parameters of the nodes inside.
    change : array
        Their move from the profile to the cubic (rad, rad/s).
    rise : float, m^2
        The model's curvature term of that move, ``change' H change``.
    touched : array or None
        The bound rows the move enters (None: no bounds).
    shift : array or None
        Those rows' change under the move.
    """

    columns: np.ndarray
    change: np.ndarray
    rise: float
    touched: np.ndarray | None
    shift: np.ndarray | None

    def breaks(self, rows_at: np.ndarray | None, bounds: LinearBounds | None) -> bool:
        """Whether the move breaks a bound row it enters (``rows_at``: every row's value)."""
        if self.touched is None:
            return False
        values = rows_at[self.touched] + self.shift
        lower, upper = bounds.lower[self.touched], bounds.upper[self.touched]
        return bool(np.any(values < lower) or np.any(values > upper))


class _Spans:
    """The spans of one coarsening, each made once (its move is fixed while its ends are kept).

    A node's removal moves only the nodes inside its own span, so a span whose two ends are
    both kept sees the same profile inside it in every pass; only the bound rows' values
    (:attr:`rows_at`) and the gradient move. A pass's new spans are made together, as arrays
    over all the nodes inside them (one at a time, the greedy passes had taken 0.055 s of
    whole-space seed 0 case 4's 0.064 s coarsening, on 120 parameters).
    """

    def __init__(self, quadratic: Quadratic, times, current: np.ndarray, bounds):
        self.quadratic, self.times, self.current, self.bounds = quadratic, times, current, bounds
        count = quadratic.count
        # Every node's angle and rate in the profile (rad, rad/s), node 0 at rest.
        self.angles = np.concatenate([[0.0], quadratic.profile[:count]])
        self.rates = np.concatenate([[0.0], quadratic.profile[count:]])
        self.rows_at = None
        if bounds is not None:
            self.rows_at = bounds.matrix @ current
        self._made: dict[tuple[int, int], _Span] = {}

    def made(self, ends: list[tuple[int, int]]) -> list[_Span]:
        """The spans between the nodes ``ends`` (pairs of indices into the times)."""
        missing = [pair for pair in dict.fromkeys(ends) if pair not in self._made]
        if missing:
            self._make(np.array(missing, dtype=int))
        return [self._made[pair] for pair in ends]

    def _make(self, pairs: np.ndarray) -> None:
        """Make the spans ``pairs`` (rows of left and right node indices) at once."""
        left, right = pairs[:, 0], pairs[:, 1]
        inside_counts = right - left - 1
        total = int(inside_counts.sum())
        owner = np.repeat(np.arange(len(pairs)), inside_counts)  # each inside node's span
        first = np.cumsum(inside_counts) - inside_counts  # its span's first inside node
        inside = left[owner] + 1 + np.arange(total) - first[owner]
        columns, change = self._moves(left[owner], right[owner], inside)
        # Each span's angles and rates, padded to the widest span's (a zero move adds nothing).
        widest = int(inside_counts.max())
        place = np.arange(total) - first[owner]
        padded_columns = np.zeros((len(pairs), 2, widest), dtype=int)
        padded_change = np.zeros((len(pairs), 2, widest))
        padded_columns[owner, :, place] = columns.T
        padded_change[owner, :, place] = change.T
        flat_columns = padded_columns.reshape(len(pairs), 2 * widest)
        flat_change = padded_change.reshape(len(pairs), 2 * widest)
        hessian = self.quadratic.hessian
        blocks = hessian[flat_columns[:, :, None], flat_columns[:, None, :]]
        rises = np.einsum("sa,sab,sb->s", flat_change, blocks, flat_change)
        shifts = None
        if self.bounds is not None:  # every span's shift of the bound rows it enters
            moves = sparse.csc_array(
                (change.ravel(), (columns.ravel(), np.tile(owner, 2))),
                shape=(hessian.shape[0], len(pairs)),
            )
            shifts = sparse.csc_array(self.bounds.sparse_matrix @ moves)
            shifts.sort_indices()
        for s, pair in enumerate(map(tuple, pairs)):
            inside_span = slice(0, int(inside_counts[s]))  # its angles, then its rates
            kept = padded_columns[s, :, inside_span].ravel()
            moved = padded_change[s, :, inside_span].ravel()
            touched = shift = None
            if shifts is not None:
                cut = slice(shifts.indptr[s], shifts.indptr[s + 1])
                touched, shift = shifts.indices[cut], shifts.data[cut]
            self._made[pair] = _Span(kept, moved, float(rises[s]), touched, shift)

    def _moves(self, left, right, inside) -> tuple[np.ndarray, np.ndarray]:
        """The columns (2, n) of the nodes ``inside`` and their moves onto one cubic each.

        Each node's cubic runs through the profile's angles and rates at its ``left`` and
        ``right`` nodes (arrays like ``inside``); row 0 holds the angles, row 1 the rates.
        """
        times, angles, rates = self.times, self.angles, self.rates
        width = times[right] - times[left]
        h00, h10, h01, h11 = hermite_polynomials((times[inside] - times[left]) / width)
        ends = (angles[left], width * rates[left], angles[right], width * rates[right])
        value = h00[0] * ends[0] + h10[0] * ends[1] + h01[0] * ends[2] + h11[0] * ends[3]
        slope = h00[1] * ends[0] + h10[1] * ends[1] + h01[1] * ends[2] + h11[1] * ends[3]
        count = self.quadratic.count
        columns = np.stack([inside - 1, inside - 1 + count])
        return columns, np.stack([value, slope / width]) - self.current[columns]

    def moved(self, span: _Span) -> None:
        """Move the profile (shared with the caller) onto the cubic of ``span``."""
        self.current[span.columns] += span.change
        if self.rows_at is not None:
            self.rows_at[span.touched] += span.shift


class Adaptation:
    """An adaptive grid's coarsening with its settings bound (what the model correction calls).

    Parameters
    ----------
    tolerance : float
        ``GridSettings.adaptive_tolerance``.
    candidates : callable, optional
        Builds the problem on the candidate nodes, where they are finer than the default grid's
        (``adaptive_finest`` > 1); called only where the coarsening takes them.

    Attributes
    ----------
    finer : WinchProblem or None
        The problem on the finer candidates, once a coarsening has taken them.
    """

    def __init__(self, tolerance: float, candidates: Callable[[], WinchProblem] | None = None):
        self.tolerance, self._candidates, self.finer = tolerance, candidates, None

    def __call__(self, problem: WinchProblem, solver, values, parameters) -> Coarsening:
        """:func:`coarsen` with these settings."""
        finer = self._finer if self._candidates is not None else None
        return coarsen(problem, solver, values, parameters, self.tolerance, finer)

    def _finer(self) -> WinchProblem:
        if self.finer is None:
            self.finer = self._candidates()
        return self.finer


def coarsen(
    problem: WinchProblem,
    solver,
    values,
    parameters: np.ndarray,
    tolerance: float,
    finer: Callable[[], WinchProblem] | None = None,
) -> Coarsening:
    """The nodes to keep, at the optimum of ``problem``'s first solve (module docstring).

    Parameters
    ----------
    problem : WinchProblem
        The problem on the default grid, solved first.
    solver : ProblemSolver
        Its solver, which solved it last at ``parameters``: a Gauss-Newton solver's last
        linearisation is taken again; another solver's problem is linearised anew.
    values : ProblemParameters
        The problem's named parameters, as its first solve took them.
    parameters : array
        The first solve's optimum on the default grid (rad, rad/s).
    tolerance : float
        ``GridSettings.adaptive_tolerance``: the nodes kept predict Omega within it of the
        default grid's prediction.
    finer : callable, optional
        Builds the problem on the candidate nodes (a grid ``adaptive_finest`` times finer,
        holding the default grid's nodes); None: the default grid's nodes are the candidates.
    """
    model = solver
    if not hasattr(model, "linearised_at"):  # a solver that keeps no linearisation of its own
        model = GaussNewton(problem, GaussNewtonSettings())
    linearised = model.linearised_at(values, parameters)
    quadratic = _optimum(model, linearised, parameters, model.final_step(values, parameters))
    predicted = float(np.sqrt(max(quadratic.objective, 0.0)))
    if finer is not None and predicted > REACH_LIMITED * quadratic.unbounded():
        finer = None  # the winch's reach, not the grid, limits Omega: finer nodes cannot help
    candidates = problem if finer is None else finer()
    times = candidates.control.breakpoints
    start = parameters
    if finer is not None:  # the model in the candidates' parameters, from the same profile
        default, model = model, GaussNewton(candidates, GaussNewtonSettings())
        start = on_nodes(problem.control, parameters, times)
        same_step = np.array_equal(candidates.grid, problem.grid)
        # The default grid's sweep carried onto them, or one sweep of their own.
        carried = _carried(default, model, linearised.jacobian) if same_step else None
        if carried is not None:
            linearised = Linearised(linearised.states, linearised.error, carried, True)
        else:
            if not same_step:  # a shorter model step: their own values
                values = candidates.parameter_values()
            linearised = model.linearisation(values, start)
        quadratic = _optimum(model, linearised, start)
    allowed = ((1 + tolerance) * predicted + OMEGA_ROUND_OFF) ** 2
    kept = np.arange(times.size)
    for _ in range(REOPTIMISED + 1):
        fewer = quadratic.coarsest(times, allowed, candidates.bounds, kept)
        if fewer.size == kept.size and fewer.size < times.size:
            break
        kept = fewer
        chosen, embedding = with_nodes(candidates, times[kept])
        coarse = on_nodes(candidates.control, quadratic.profile, times[kept])
        # The model's optimum on the nodes kept (a QP within their bounds), from which the
        # next pass removes more: the interpolated profile overstates what they cost.
        moved = linearised.jacobian @ (quadratic.profile - start)
        on_chosen = Linearised(
            linearised.states, linearised.error + moved, linearised.jacobian @ embedding, True
        )
        reduced = GaussNewton(chosen, GaussNewtonSettings())
        bounds = chosen.bounds
        step, _, _ = reduced.step(on_chosen, coarse, bounds.lower, bounds.upper, {})
        if step is None:
            break
        quadratic.moved(embedding @ step)
    parameters = coarse + (step if step is not None else 0.0)
    error = on_chosen.error + on_chosen.jacobian @ (parameters - coarse)
    return Coarsening(
        chosen,
        parameters,
        problem.control.intervals,
        predicted,
        float(np.sqrt(max(quadratic.objective, 0.0))),
        times,
        Linearised(linearised.states, error, on_chosen.jacobian, True),
        values,
        problem.step,
    )


def _carried(default: GaussNewton, finer: GaussNewton, jacobian: np.ndarray) -> np.ndarray | None:
    """The default grid's Jacobian ``jacobian`` in the finer candidates' parameters, or None.

    Only the parameters of the candidates between the default grid's nodes are propagated
    (:meth:`ErrorLinearisation.carried`); those of the default grid's own nodes follow from
    ``J_default = J_finer E`` (``E``, the default profile on the candidates, is the identity
    on the default grid's own nodes): half the propagation (its 0.2 s on whole-space seed 0
    case 8's 468 candidate parameters).
    """
    coarse, fine = default.problem.control, finer.problem.control
    embedding = on_nodes(coarse, np.eye(coarse.size), fine.breakpoints)
    scale = fine.breakpoints[-1]
    shared = np.abs(fine.breakpoints[1:, None] - coarse.breakpoints[None, 1:]) <= 1e-9 * scale
    node, own = np.nonzero(shared)  # candidate node (from 1) and default node (from 1) alike
    if not np.array_equal(own, np.arange(coarse.breakpoints.size - 1)):
        return None
    count = fine.breakpoints.size - 1
    held = np.concatenate([node, node + count])  # the default nodes' angles, then rates
    between = np.setdiff1d(np.arange(fine.size), held)
    carried = finer.linearisation.carried(default.linearisation, jacobian, between)
    if carried is None:
        return None
    result = np.empty((jacobian.shape[0], fine.size))
    result[:, between] = carried
    result[:, held] = jacobian - carried @ embedding[between]
    return result


def _optimum(
    model: GaussNewton, linearised, profile: np.ndarray, step: np.ndarray | None = None
) -> Quadratic:
    """The Gauss-Newton model at ``profile``, moved to its QP's optimum within the bounds.

    ``step``: that QP's step where the solve that ended at ``profile`` took it last
    (:meth:`GaussNewton.final_step`); None: solved here.
    """
    quadratic = Quadratic(
        model.weights * linearised.error, model.weights[:, None] * linearised.jacobian, profile
    )
    if step is None:
        bounds = model.problem.bounds
        step, _, _ = model.step(linearised, profile, bounds.lower, bounds.upper, {})
    if step is not None:
        quadratic.moved(step)
    return quadratic
