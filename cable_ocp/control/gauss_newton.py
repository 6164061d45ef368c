"""Gauss-Newton SQP on a winch problem: Omega^2 is a least-squares, so its Hessian is ``2 J^T J``.

Each iteration linearises the clearance error on the problem's grid (one simulation of the
optimisation model with its sensitivities, :mod:`cable_ocp.control.linearisation`) and solves
the quadratic programme

    min  |W (e + J d)|^2 + w |W_r (r_D phi'(p + d))|^2     s.t.  bounds on p + d

with DAQP (a dual active-set solver for dense QPs; silent, and twice as fast as qpOASES on
a 42-parameter, 360-row QP), the winch bounds being the problem's Bernstein constraints (held
between the RK4 samples, :mod:`cable_ocp.drive.bounds`), screened to the rows near their limits.
The open loop iterates to convergence with a backtracking line search, whose trial points need
the error alone (a simulation without sensitivities, a twentieth of the cost); the Jacobian is
evaluated again at an accepted point only when the last one mispredicted its error (a simplified
Newton method otherwise), and a model-correction solve starts from the last solve's
linearisation with only its bias changed. On paper_hill's default optimisation that is two
simulations with sensitivities over three solves and eight iterations, against eight before.
The closed loop takes one step per sample from the shifted previous plan (a real-time
iteration, as acados does), so that a solve costs one simulation with sensitivities and one
small QP.
"""

from __future__ import annotations

import time
from copy import deepcopy
from dataclasses import dataclass
from functools import cached_property

import casadi as ca
import numpy as np
from scipy.ndimage import maximum_filter1d

from cable_ocp.control.checks import Rule, check_fields
from cable_ocp.control.interrupts import check, keeping_interrupts
from cable_ocp.control.linearisation import (
    STAGE_JACOBIANS,
    ErrorLinearisation,
    Linearised,
    rhs_jacobian,
)
from cable_ocp.control.parameters import ProblemParameters
from cable_ocp.control.problem import ProblemSolver, SolverOutcome, WinchProblem
from cable_ocp.drive.bounds import shrunk
from cable_ocp.drive.drive import stage_times
from cable_ocp.simulation.progress import IterationLog
from cable_ocp.simulation.seabed import trapezoid_weights

# The QP is first solved on the constraint rows within this distance of their limits (rad, rad/s,
# rad/s^2), in the smallest of these QPs that holds them; rows its solution breaks are added, and
# a QP too small for them gives way to the next (constraint screening,
# :meth:`GaussNewton._screened_solve`). A QP's cost grows with its rows (DAQP scales every row by
# the Hessian's factor): on whole-space seed 0 case 6 (120 parameters) the whole QP of 16200
# rows took 0.31-0.63 s, one of 3840 rows 0.05 s, one of 960 rows 0.014-0.025 s.
SCREEN_DISTANCE = 1e-2
SCREENED_ROWS = (120, 240, 480, 960, 1920, 3840, 7680)
# Broken rows that do not fit in the QP at hand are thinned to those that break theirs most within
# this many rows either side (a step that cuts across a bound breaks a run of neighbouring rows,
# which one of them holds nearly as well): on that case a Gauss-Newton step broke more rows than
# 7680, and thinned rounds of 960 and 1920 rows solved its QP in 0.21 s against 0.61 s whole
# (``cable-ocp bench --only qp``); all broken rows are added where they fit.
SCREEN_NEIGHBOURS = 4
# Levenberg-Marquardt damping of the QP's Hessian, relative to its largest diagonal entry: it
# keeps the QP strictly convex where a parameter barely moves the error (the horizon's last rate).
DAMPING = 1e-9
# DAQP holds its constraints to about 1e-5 (measured 9e-6 and 1.6e-5 rad beyond angle_max on two
# of 20 robustness cases, over the verification's 1e-6 rad): the QP takes the winch bounds this
# much inside (rad, rad/s, rad/s^2; 25 um of top element at r_D = 0.5 m).
QP_MARGIN = 5e-5
# DAQP's active-set iterations per QP (its default, 1000, ran out on a 198-parameter QP with rate
# and acceleration rows: whole-space robustness case 9 of seed 0).
QP_ITERATIONS = 20_000
# Price of the closed loop's clearance slack (per m and m^2, against Omega^2 in m^2), and the
# slack (m) above which a solve's status says it was used.
SOFT_PRICE = 1e3
SOFT_REPORTED = 1e-6
# Iterations stop as converged once Omega^2 changes by less than this share over this many
# accepted steps (IPOPT's acceptable_obj_change_tol and acceptable_iter of the open loop's
# options): a reach-limited whole-space case crawled along its bounds for 300 iterations.
STALL_CHANGE, STALL_ITERATIONS = 1e-3, 5
# A step is accepted once it achieves this fraction of the decrease the QP predicted (Armijo).
ARMIJO = 1e-4
BACKTRACKS = 12
# A predicted decrease below this share of Omega^2 that the line search cannot realise is
# round-off: the iterations have converged.
NEGLIGIBLE = 1e-3
DAQP_INFEASIBLE = (
    "Infeasible: no winch profile meets the winch bounds (and seabed.minimum_clearance, where "
    "set) (DAQP exit flag -1)"
)
# The minimum clearance is imposed this far (m) above seabed.minimum_clearance on the
# optimisation model: the verification (on the full model) allows 1 mm under it.
CLEARANCE_BACKOFF = 1e-3
# A run this far (m) under the backed-off minimum clearance counts as within it.
BREACH_TOLERANCE = 1e-4
# The Jacobian is kept for the next step while it predicted the error at the accepted point to
# within this share of that error (weighted 2-norms).
STALE_JACOBIAN = 0.05


@dataclass(frozen=True)
class GaussNewtonSettings:
    """How the Gauss-Newton iterations run.

    Attributes
    ----------
    max_iter : int
        Iterations (one linearisation and one QP each; 300, IPOPT's count, in the open loop).
    real_time : bool
        Take ``max_iter`` full steps without a line search or a convergence test (a closed
        loop's real-time iteration, warm-started from its previous plan); its result is the last
        step's, not simulated again.
    tolerance : float
        Stop when the QP predicts a decrease of Omega^2 below ``tolerance`` times Omega^2 (and
        below ``tolerance`` times (1 mm)^2, so that an Omega near zero stops too).
    stage_jacobians : {"every", "ends"}
        Where the sensitivities take the model's Jacobian: at every RK4 stage (exact), or at
        the step ends only (a closed loop's real-time iteration,
        :mod:`cable_ocp.control.linearisation`).
    """

    max_iter: int = 300
    tolerance: float = 1e-6
    real_time: bool = False
    stage_jacobians: str = "every"

    def __post_init__(self):
        check_fields(
            self,
            {
                "max_iter": Rule("integer", low=1),
                "tolerance": Rule("number", above=0),
                "stage_jacobians": Rule("choice", choices=STAGE_JACOBIANS),
            },
        )


class GaussNewton(ProblemSolver):
    """The Gauss-Newton SQP of a :class:`WinchProblem`, built once and solved as often as needed.

    Parameters
    ----------
    problem : WinchProblem
    settings : GaussNewtonSettings
    log : IterationLog, optional
        One line per iteration (None: nothing).
    rate_weight : float, s^2
        Weight of the pay-out speed ``(r_D phi')^2`` against ``e^2`` (0 in the open loop).
    """

    def __init__(
        self,
        problem: WinchProblem,
        settings: GaussNewtonSettings,
        log: IterationLog | None = None,
        rate_weight: float = 0.0,
    ):
        started = time.perf_counter()
        self.problem, self.settings, self.log = problem, settings, log
        steps = problem.grid.size - 1
        radius = problem.scene.winch.drum_radius
        self.compile_time = rhs_jacobian(problem.model)[1].compile_time  # waits for its compiler
        span = problem.grid[-1] - problem.grid[0]
        self.weights = np.sqrt(trapezoid_weights(problem.step, problem.grid.size) / span)
        self.rate_rows = np.zeros((0, problem.control.size))  # the open loop's: no rate term
        if rate_weight > 0:
            rates = radius * problem.control.basis(problem.grid)[1]
            self.rate_rows = np.sqrt(rate_weight) * self.weights[:, None] * rates
        bounds, seabed = problem.bounds, problem.scene.seabed
        size = problem.control.size
        # The hard minimum clearance: delta + e >= c_min (+ a back-off) at every RK4 point after
        # the start, linearised as the error is.
        self.floor = None
        if seabed.minimum_clearance is not None:
            self.floor = seabed.minimum_clearance + CLEARANCE_BACKOFF - seabed.clearance
        rows = bounds.matrix.shape[0] + (steps if self.floor is not None else 0)
        # A closed loop's QP takes the clearance rows soft: one slack (m) that every row may use,
        # at a price (:data:`SOFT_PRICE`), so that a start already under the floor (a heave, the
        # plant's error) still has a plan; the slack used is reported in the status.
        self.soft = settings.real_time and self.floor is not None
        self._qp_shape = (size + self.soft, rows)  # variables, rows
        self._qps: dict[int, ca.Function] = {}  # by rows, built at their first use
        if settings.real_time:  # a controller's every QP and its sweep before its first sample
            for width in {min(width, rows) for width in SCREENED_ROWS} | {rows}:
                self._qp(width)
            self.linearisation  # noqa: B018 (built here, not at the first sample)
        self.softened = 0.0  # m: the slack of the last step
        self._last: tuple[ProblemParameters, np.ndarray, Linearised] | None = None
        # The QP step the last solve took at its end, within the problem's own bounds (None:
        # it ended elsewhere), which the adaptive grid's coarsening takes again.
        self._final_step: np.ndarray | None = None
        self.build_time = time.perf_counter() - started

    @cached_property
    def linearisation(self) -> ErrorLinearisation:
        """The error and its Jacobian along the problem's horizon, built at its first use.

        Its map of the winch parameters onto every stage's inputs takes a share of a build (the
        adaptive grid's coarsening takes QP steps only, on two or three problems).
        """
        problem = self.problem
        times, left = stage_times(problem.grid[:-1], problem.step)
        return ErrorLinearisation(
            problem.model, problem.step, problem.grid.size - 1, problem.control,
            problem.scene.winch.drum_radius, problem.scene.seabed, times, left,
            self.settings.stage_jacobians,
        )  # fmt: skip

    def objective(self, linearised: Linearised, parameters: np.ndarray) -> float:
        """Omega^2 (m^2), with the rate term."""
        residual = self.weights * linearised.error
        rates = self.rate_rows @ parameters
        return float(residual @ residual + rates @ rates)

    def feasible(
        self, parameters: np.ndarray, lower: np.ndarray, upper: np.ndarray, fixed: dict
    ) -> np.ndarray:
        """The point nearest ``parameters`` within the winch bounds (``parameters`` if inside).

        A least-distance QP on the bounds' rows (the minimum clearance aside); a guess no point
        can bring inside is returned as it is (the first QP then reports the infeasibility).
        """
        matrix = self.problem.bounds.matrix
        values = matrix @ parameters
        # A QP's solution counts as inside: DAQP leaves its rows by up to 1.6e-5 (QP_MARGIN), and
        # moving it again would cost the adaptive grid's carried Jacobian (whole-space seed 0
        # case 6: 2.8e-6 rad out, one sensitivity sweep of 0.5 s).
        held_lower, held_upper = shrunk(lower, upper, QP_MARGIN / 2)
        pinned = all(parameters[i] == value for i, value in fixed.items())
        if pinned and np.all(values >= held_lower) and np.all(values <= held_upper):
            return parameters
        lower, upper = shrunk(lower, upper, QP_MARGIN)
        size = parameters.size  # no slack: the open loop's QPs are hard (self.soft is False)
        lbx, ubx = _pinned_steps(parameters, fixed)
        step, _ = self._screened_solve(
            np.eye(size), np.zeros(size), matrix, lower - values, upper - values, lbx, ubx
        )
        if step is None:
            return parameters
        return parameters + step

    def breach(self, linearised: Linearised) -> float:
        """How far (m) the run goes under the minimum clearance with its back-off (0: not)."""
        if self.floor is None or not linearised.finite:
            return 0.0 if self.floor is None else float("inf")
        return float(max(np.max(self.floor - linearised.error[1:]), 0.0))

    def step(
        self,
        linearised: Linearised,
        parameters: np.ndarray,
        lower: np.ndarray,
        upper: np.ndarray,
        fixed: dict[int, float],
    ) -> tuple[np.ndarray | None, float, str]:
        """The QP's step ``d`` from ``parameters``, its predicted decrease and DAQP's status.

        ``lower``, ``upper`` bound ``bounds.matrix @ (p + d)``; ``fixed`` pins parameters.
        """
        jacobian = self.weights[:, None] * linearised.jacobian
        residual = self.weights * linearised.error
        hessian = jacobian.T @ jacobian + self.rate_rows.T @ self.rate_rows
        gradient = jacobian.T @ residual + self.rate_rows.T @ (self.rate_rows @ parameters)
        hessian[np.diag_indices_from(hessian)] += DAMPING * max(np.max(np.diag(hessian)), 1e-30)
        matrix = self.problem.bounds.matrix
        values = matrix @ parameters
        lower, upper = shrunk(lower, upper, QP_MARGIN)
        lba, uba = lower - values, upper - values
        if self.floor is not None:
            matrix = np.vstack([matrix, linearised.jacobian[1:]])
            lba = np.concatenate([lba, self.floor - linearised.error[1:]])
            uba = np.concatenate([uba, np.full(linearised.error.size - 1, np.inf)])
        lbx, ubx = _pinned_steps(parameters, fixed)
        if self.soft:
            hessian, gradient, matrix, lbx, ubx = _with_slack(
                hessian, gradient, matrix, self.problem.bounds.matrix.shape[0], lbx, ubx
            )
        step, status = self._screened_solve(hessian, gradient, matrix, lba, uba, lbx, ubx)
        if step is None:
            return None, 0.0, status
        if self.soft:
            self.softened = max(float(step[-1]), 0.0)
            hessian, gradient, step = hessian[:-1, :-1], gradient[:-1], step[:-1]
        predicted = -float(gradient @ step + 0.5 * step @ hessian @ step)
        return step, 2 * predicted, "solved"

    def _screened_solve(self, hessian, gradient, matrix, lba, uba, lbx, ubx):
        """The QP's solution ``(step, "solved")``, or ``(None, reason)``, by constraint screening.

        Of the winch bounds' Bernstein rows (1680 on paper_hill) few are ever near active: the QP
        is solved on the rows within :data:`SCREEN_DISTANCE` of their limits, and rows that its
        solution breaks are added until none is (the relaxed QP's solution then solves the whole
        QP). Broken rows that do not fit are thinned (:func:`_worst_nearby`) and the QP goes on
        to the next, larger one (:data:`SCREENED_ROWS`); more rows than the largest holds go on
        to the whole QP.
        """
        kept = np.flatnonzero((-lba < SCREEN_DISTANCE) | (uba < SCREEN_DISTANCE))
        whole = self._qp_shape[1]
        for width in sorted({min(width, whole) for width in SCREENED_ROWS}):
            if matrix.shape[0] <= width:
                kept = np.arange(matrix.shape[0])
            while kept.size <= width:
                rows = _padded(matrix[kept], lba[kept], uba[kept], width)
                qp = self._qp(width)
                step, status = _solved(qp, h=hessian, g=gradient, **rows, lbx=lbx, ubx=ubx)
                if step is None:
                    return None, status
                values = matrix @ step
                excess = np.maximum(lba - values, values - uba)
                excess[kept] = 0.0
                broken = np.flatnonzero(excess > 0)
                if broken.size == 0:
                    return step, status
                if kept.size + broken.size > width:
                    broken = _worst_nearby(excess)
                kept = np.union1d(kept, broken)
        return self._whole_solve(hessian, gradient, matrix, lba, uba, lbx, ubx)

    def _whole_solve(self, hessian, gradient, matrix, lba, uba, lbx, ubx):
        """The QP on every row at once (what screening falls back on, and its benchmark's base).

        The whole QP holds every row of a step's QP (the clearance rows too); a QP on the
        bounds alone (feasible) fills the rest.
        """
        rows = _padded(matrix, lba, uba, self._qp_shape[1])
        qp = self._qp(self._qp_shape[1])
        return _solved(qp, h=hessian, g=gradient, **rows, lbx=lbx, ubx=ubx)

    def _qp(self, rows: int) -> ca.Function:
        """The dense QP of ``rows`` constraint rows (DAQP), built at its first use.

        A dense sparsity of 3000 rows takes milliseconds to build, and most solvers never need
        the whole QP (nor the adaptive grid's coarsening, which only takes QP steps, its wider
        screened ones).
        """
        if rows not in self._qps:
            self._qps[rows] = _dense_qp(f"gauss_newton_qp_{rows}", self._qp_shape[0], rows)
        return self._qps[rows]

    def run(self, values, guess, fixed, lower, upper) -> SolverOutcome:
        """Iterate from ``guess`` (:meth:`ProblemSolver.solve`).

        The outcome's ``states`` are the model's run under its parameters (None after a
        real-time iteration, which does not simulate its result).
        """
        with keeping_interrupts() as seen:
            return self._solve(values, guess, fixed, lower, upper, seen)

    def _solve(
        self,
        values: ProblemParameters,
        guess: np.ndarray,
        fixed: dict[int, float] | None,
        lower: np.ndarray | None,
        upper: np.ndarray | None,
        seen: list[int],
    ) -> SolverOutcome:
        """:meth:`solve`, stopping at once when ``seen`` records a SIGINT."""
        settings, bounds = self.settings, self.problem.bounds
        lower = bounds.lower if lower is None else lower
        upper = bounds.upper if upper is None else upper
        fixed = fixed or {}
        started = time.perf_counter()
        function_time = 0.0
        parameters = np.array(guess, dtype=float)
        if not settings.real_time:
            # The line search moves between feasible points only (the bounds are linear), so
            # that the result holds them: start from the guess's nearest feasible point.
            parameters = self.feasible(parameters, lower, upper, fixed)
        begun = time.perf_counter()
        current = self.linearised_at(values, parameters)
        function_time += time.perf_counter() - begun
        history, status, success, iterations = [], "", False, 0
        final_step = None
        refreshed = False  # the Jacobian in use was evaluated at the current point
        if self.log is not None:
            self.log.restart()
        if not current.finite:
            status = "the optimisation model blew up under the initial guess"
        else:
            cost = self.objective(current, parameters)
            history.append(cost)
            self._report(history, parameters, lower, upper)
        while current.finite and iterations < settings.max_iter:
            check(seen)
            iterations += 1
            step, predicted, qp_status = self.step(current, parameters, lower, upper, fixed)
            final_step = step  # the QP at the end, until the iterations move on
            if step is None:
                status = f"the QP failed: {qp_status}"
                break
            if settings.real_time:  # take the full step, unchecked
                parameters = parameters + step
                if iterations < settings.max_iter:
                    current = self.linearisation(values, parameters)
                    if current.finite:
                        continue
                status = f"{iterations} Gauss-Newton step(s) (real-time iteration)"
                if self.softened > SOFT_REPORTED:
                    status += (
                        f"; the minimum clearance softened by {self.softened:.3g} m (the plan "
                        "could not keep it from the state it started in)"
                    )
                success = True
                break
            breach = self.breach(current)
            if predicted <= settings.tolerance * max(cost, 1e-6) and breach <= BREACH_TOLERANCE:
                status, success = "converged: the predicted decrease is below tolerance", True
                break
            accepted = False
            fraction = 1.0
            for _ in range(BACKTRACKS):
                trial = parameters + fraction * step
                begun = time.perf_counter()
                candidate = self.linearisation.error(values, trial)
                function_time += time.perf_counter() - begun
                if candidate.finite:
                    trial_cost = self.objective(candidate, trial)
                    trial_breach = self.breach(candidate)
                    # A filter: less Omega^2 within the minimum clearance, or a run that goes
                    # less far under it (restoration).
                    better = trial_cost <= cost - ARMIJO * fraction * predicted
                    feasible = trial_breach <= max(breach, BREACH_TOLERANCE)
                    if (better and feasible) or trial_breach < (1 - ARMIJO) * breach:
                        accepted = True
                        break
                fraction /= 2
            if not accepted and not refreshed:
                # The Jacobian may be a kept one (or the last solve's): evaluate it here and
                # try again before giving up (a reach-limited whole-space case stalled so).
                begun = time.perf_counter()
                current = self.linearisation(values, parameters)
                function_time += time.perf_counter() - begun
                refreshed = True
                continue
            if not accepted:
                # Round-off: near the optimum the predicted decrease is below what the
                # simulation resolves.
                success = predicted <= NEGLIGIBLE * cost and breach <= BREACH_TOLERANCE
                status = (
                    "converged: no decrease left along the Gauss-Newton step"
                    if success
                    else "the line search found no decrease"
                    + (f" (the end {breach:.3g} m under the minimum clearance)" if breach else "")
                )
                break
            refreshed = False
            begun = time.perf_counter()
            current = self._linearised_after(values, current, candidate, trial, fraction * step)
            function_time += time.perf_counter() - begun
            parameters, cost, final_step = trial, trial_cost, None
            history.append(cost)
            self._report(history, parameters, lower, upper)
            if _stalled(history) and trial_breach <= BREACH_TOLERANCE:
                status, success = (
                    (
                        f"converged: Omega^2 changed by less than {STALL_CHANGE:.1%} over "
                        f"{STALL_ITERATIONS} iterations"
                    ),
                    True,
                )
                break
        else:
            if current.finite and not status:
                status = f"stopped at max_iter = {settings.max_iter}"
        solve_time = time.perf_counter() - started
        # Where the next solve may start (copied: a caller may refill its arrays in place); a
        # real-time iteration ends away from its last linearisation.
        self._last = None if settings.real_time else (deepcopy(values), parameters, current)
        own_bounds = not fixed and lower is bounds.lower and upper is bounds.upper
        self._final_step = final_step if own_bounds and current.finite else None
        omega = float(np.sqrt(max(history[-1], 0.0))) if history else float("nan")
        outcome = SolverOutcome(
            parameters=parameters,
            status=status,
            success=success,
            iterations=iterations,
            evaluations=len(history),
            omega=omega,
            build_time=self.build_time,
            compile_time=self.compile_time,
            solve_time=solve_time,
            function_time=function_time,
            history=history,
            states=current.states if current.finite and not settings.real_time else None,
        )
        return outcome

    def _linearised_after(
        self,
        values: ProblemParameters,
        before: Linearised,
        after: Linearised,
        parameters: np.ndarray,
        step: np.ndarray,
    ) -> Linearised:
        """The linearisation at an accepted point, whose error ``after`` is known.

        The Jacobian is evaluated again (a simulation with sensitivities) unless the last one
        predicted the new error to within :data:`STALE_JACOBIAN` of it (weighted 2-norms): then
        it is kept, as in a simplified Newton method. A model-correction solve moves the winch by
        a fraction of a millimetre, along which the Jacobian does not change.
        """
        if self._predicts(before.error + before.jacobian @ step, after.error):
            return Linearised(after.states, after.error, before.jacobian, True)
        return self.linearisation(values, parameters)

    def _predicts(self, predicted: np.ndarray, error: np.ndarray) -> bool:
        """Whether ``predicted`` is within :data:`STALE_JACOBIAN` of ``error`` (weighted norms).

        The test by which a Jacobian evaluated elsewhere is kept (simplified Newton).
        """
        mismatch = np.linalg.norm(self.weights * (error - predicted))
        return bool(mismatch <= STALE_JACOBIAN * np.linalg.norm(self.weights * error))

    def start_from(
        self, values: ProblemParameters, parameters: np.ndarray, predicted: Linearised
    ) -> bool:
        """Let the next solve from ``parameters`` start with the Jacobian of ``predicted``.

        ``predicted`` is an error and Jacobian at ``parameters`` carried over from another
        linearisation (the adaptive grid's, from the default grid's). One run without
        sensitivities (a twentieth of a sweep) gives the error; the Jacobian is kept, as in a
        simplified Newton method, if it predicted that error within :data:`STALE_JACOBIAN`
        (weighted 2-norms), and the solve then evaluates it again only where its line search
        fails. Returns whether it was kept.
        """
        parameters = np.array(parameters, dtype=float)
        run = self.linearisation.error(values, parameters)
        if not run.finite or not self._predicts(predicted.error, run.error):
            return False
        kept = Linearised(run.states, run.error, predicted.jacobian, True)
        self._last, self._final_step = (deepcopy(values), parameters, kept), None
        return True

    def linearised_at(self, values: ProblemParameters, parameters: np.ndarray) -> Linearised:
        """The linearisation at ``parameters``, reusing the last solve's end if it is there.

        A model-correction solve starts where the last one ended, with only the bias changed:
        the run and the Jacobian are the same, the error moves by the change of the bias (the
        adaptive grid's coarsening takes it so too, :mod:`cable_ocp.control.adaptive_grid`).
        """
        if self._last is not None:
            last_values, last_parameters, last = self._last
            if (
                last.finite
                and np.array_equal(parameters, last_parameters)
                and values.same_run(last_values)
            ):
                error = last.error + (values.bias - last_values.bias)
                return Linearised(last.states, error, last.jacobian, True)
        return self.linearisation(values, parameters)

    def final_step(self, values: ProblemParameters, parameters: np.ndarray) -> np.ndarray | None:
        """The QP step that the last solve took at its end, if it ended at ``parameters``.

        The step :meth:`step` gives from there within the problem's own bounds (nothing fixed),
        for ``values`` the solve's own (the same run and bias); None where the solve did not
        end on a QP at that point (it stalled, or stopped at ``max_iter``). The adaptive grid's
        coarsening starts from it (whole-space seed 1 case 45: a QP of 0.22 s, on 158 parameters
        and 6952 rows).
        """
        if self._final_step is None or self._last is None:
            return None
        last_values, last_parameters, _ = self._last
        same = np.array_equal(parameters, last_parameters) and values.same_run(last_values)
        if not same or not np.array_equal(values.bias, last_values.bias):
            return None
        return self._final_step

    def _report(self, history: list[float], parameters, lower, upper) -> None:
        """One log line: the iteration, Omega and the excess over the bounds."""
        if self.log is None:
            return
        excess = self.problem.bounds.excess(parameters, lower, upper)
        self.log.line(len(history) - 1, float(np.sqrt(max(history[-1], 0.0))), excess)


def _stalled(history: list[float]) -> bool:
    """Whether Omega^2 fell by less than :data:`STALL_CHANGE` over :data:`STALL_ITERATIONS`."""
    if len(history) <= STALL_ITERATIONS:
        return False
    return history[-1 - STALL_ITERATIONS] - history[-1] <= STALL_CHANGE * history[-1]


def _with_slack(hessian, gradient, matrix, bound_rows: int, lbx, ubx):
    """The QP with one slack ``s >= 0`` added to every clearance row (those after the bounds').

    Its price is ``SOFT_PRICE (s + s^2)`` (per m, m^2, against Omega^2 in m^2): linear, so that a
    small breach is not bought cheaply, and quadratic, so that the QP stays strictly convex.
    """
    size = gradient.size
    extended = np.zeros((size + 1, size + 1))
    extended[:size, :size] = hessian
    extended[size, size] = 2 * SOFT_PRICE
    column = np.zeros((matrix.shape[0], 1))
    column[bound_rows:] = 1.0
    return (
        extended,
        np.append(gradient, SOFT_PRICE),
        np.hstack([matrix, column]),
        np.append(lbx, 0.0),
        np.append(ubx, np.inf),
    )


def _worst_nearby(excess: np.ndarray) -> np.ndarray:
    """The broken rows (``excess > 0``) that break theirs most among their neighbours.

    Rows are in order of time within each bound (sub-intervals, then Bernstein coefficients)
    and within the clearance rows; a neighbour is within :data:`SCREEN_NEIGHBOURS` rows. Ties
    keep all of them, so every run of broken rows gives at least one.
    """
    peaks = maximum_filter1d(excess, 2 * SCREEN_NEIGHBOURS + 1, mode="constant")
    return np.flatnonzero((excess > 0) & (excess >= peaks))


def _dense_qp(name: str, size: int, rows: int) -> ca.Function:
    """DAQP on a dense QP of ``size`` variables and ``rows`` constraint rows (silent)."""
    return ca.conic(
        name,
        "daqp",
        {"h": ca.Sparsity.dense(size, size), "a": ca.Sparsity.dense(rows, size)},
        {"error_on_fail": False, "daqp": {"iter_limit": QP_ITERATIONS}},
    )


def _padded(matrix: np.ndarray, lba: np.ndarray, uba: np.ndarray, width: int) -> dict:
    """Constraint rows filled up to a QP's ``width`` with rows of zeros in [-1, 1] (always held)."""
    padding = width - matrix.shape[0]
    return {
        "a": np.vstack([matrix, np.zeros((padding, matrix.shape[1]))]),
        "lba": np.concatenate([lba, np.full(padding, -1.0)]),
        "uba": np.concatenate([uba, np.full(padding, 1.0)]),
    }


def _solved(qp: ca.Function, **data) -> tuple[np.ndarray | None, str]:
    """``(x, "solved")`` of a QP, or ``(None, why)`` when DAQP fails."""
    solution = qp(**data)
    stats = qp.stats()
    if not stats["success"]:
        flag = stats["return_status"]
        return None, DAQP_INFEASIBLE if flag == -1 else f"DAQP exit flag {flag}"
    return np.array(solution["x"]).ravel(), "solved"


def _pinned_steps(parameters: np.ndarray, fixed: dict[int, float]) -> tuple[np.ndarray, ...]:
    """Bounds of a step from ``parameters`` that lands the ``fixed`` ones on their values."""
    lbx, ubx = np.full(parameters.size, -np.inf), np.full(parameters.size, np.inf)
    for index, value in fixed.items():
        lbx[index] = ubx[index] = value - parameters[index]
    return lbx, ubx
