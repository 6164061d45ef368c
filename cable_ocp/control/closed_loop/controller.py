"""The controller: the receding-horizon winch problem, transcribed once and solved every sample.

The problem over one horizon (:meth:`cable_ocp.control.problem.WinchProblem.receding`) is the open
loop's, on the controller's reduced model: a free-start Hermite angle on intervals of
``MpcSettings.interval`` (its first ``MpcSettings.first_interval`` long), the winch bounds held
between the samples (:mod:`cable_ocp.drive.bounds`), the same stage grid and clearance error. Its
named parameters (:mod:`cable_ocp.control.parameters`) take the estimate at each sample: the reduced
state, the forecast top motion, the end force over the horizon, the end offset (measured end minus
the reduced end, :mod:`.projection`), the clearance reference, and on a landing its reference over
the horizon (in the bias, :mod:`cable_ocp.simulation.landing_reference`). The solver is the open
loop's transcription: one Gauss-Newton step from the plan in force moved on to the sample (the
real-time iteration), or IPOPT on the multiple-shooting NLP (the earlier path, kept as the
baseline).

Objective: ``1/H int e^2 dt + w 1/H int (r_D phi')^2 dt`` on the RK4 grid; the first node is held
at the angle and rate the winch has now, and the angle range is narrowed by the room the heave
feedback needs (phased in over the first sample).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from cable_ocp.control.closed_loop.forecast import TopForecast
from cable_ocp.control.closed_loop.settings import MpcSettings
from cable_ocp.control.parameters import ProblemParameters
from cable_ocp.control.problem import WinchProblem
from cable_ocp.control.settings import GridSettings, OcpSettings, TranscriptionSettings
from cable_ocp.control.solvers import SOLVERS
from cable_ocp.drive.drive import end_force, stage_times
from cable_ocp.simulation.landing_reference import reference_error

# In a solve's status when it ran on the winch's own range, its narrowed one being infeasible.
WIDENED = "on the winch's own range: the room for the heave feedback left no feasible plan"


@dataclass(frozen=True)
class Estimate:
    """What the controller knows at a sample.

    Attributes
    ----------
    state : array
        The reduced model's state projected from the plant's (:mod:`.projection`).
    forecast : TopForecast
    end_offset : array (3,), m
        Measured end minus the reduced model's end.
    reference : float, m
        Clearance reference ``z_E(0) - z(E(0))`` of the plant's start.
    margin : float, rad
        Room the plan keeps from each angle bound for the heave feedback.
    start_error : float, m
        The clearance error of the plant's start: a landing's reference starts there
        (:mod:`~cable_ocp.simulation.landing_reference`).
    """

    state: np.ndarray
    forecast: TopForecast
    end_offset: np.ndarray
    reference: float
    margin: float
    start_error: float = 0.0


@dataclass(frozen=True)
class Solve:
    """One solve of the receding-horizon problem.

    Attributes
    ----------
    parameters : array
        The plan: free-start Hermite parameters (rad, rad/s), time from the solve's start.
    status : str
        The solver's status in its own words (with :data:`WIDENED` when it solved again on the
        winch's own range), or why nothing was solved.
    success : bool
        The solver converged (the plan then takes effect; a failed one leaves the plan in force).
    iterations : int
        The solver's iterations (of the second solve when it solved again).
    solve_time : float, s
        Wall time inside the solver (of both solves when it solved again).
    by_policy : bool
        A learned policy's action made the plan, not a solve (:func:`~.loop.mpc`'s
        ``policy``); ``solve_time`` is then its evaluation's.
    """

    parameters: np.ndarray
    status: str
    success: bool
    iterations: int
    solve_time: float
    by_policy: bool = False


class RecedingHorizon:
    """The receding-horizon controller of a scene (see the module docstring).

    Parameters
    ----------
    scene : Scene
    settings : MpcSettings
    """

    def __init__(self, scene, settings: MpcSettings):
        self.scene, self.settings = scene, settings
        self.problem = problem = WinchProblem.receding(
            scene, settings.plan_nodes, settings.elements, settings.step
        )
        self.model, self.control = problem.model, problem.control
        self.entry = entry = SOLVERS[settings.solver]
        transcription = OcpSettings(
            settings.solver,
            entry.warm_started(settings.solver_settings),
            settings.model,
            GridSettings(control=entry.default_control, intervals=settings.intervals),
            TranscriptionSettings(shooting=entry.closed_loop_shooting),
        )
        self.solver = entry.build(problem, transcription, True, False, settings.rate_weight)
        self.build_time, self.compile_time = self.solver.build_time, self.solver.compile_time
        self.stage_times = stage_times(problem.grid[:-1], problem.step)[0]
        self.plan, self.plan_start = np.zeros(self.control.size), 0.0
        self._start_angle, self._start_rate = self.control.node_indices(0)
        # The top element at phi = 0, before the plan: the nominal length, at rest.
        self._base = np.zeros((3, self.stage_times.size))
        self._base[0] = self.model.spec.top_length

    def parameter_values(self, now: float, estimate: Estimate) -> ProblemParameters:
        """The named parameters at the sample ``now`` (s) from the estimate."""
        times = self.stage_times
        forecast = estimate.forecast
        motion = np.vstack(
            [
                forecast.position[:, None] + forecast.velocity[:, None] * times[None, :],
                np.repeat(forecast.velocity[:, None], times.size, axis=1),
                np.zeros((3, times.size)),
            ]
        )
        return ProblemParameters(
            initial_state=estimate.state,
            top_motion=motion,
            winch_base=self._base,
            end_force=end_force(self.scene.end, now + times),
            reference=estimate.reference,
            end_offset=np.asarray(estimate.end_offset, dtype=float),
            # A landing's reference over the horizon; zero on other scenes.
            bias=-reference_error(self.scene, now + self.problem.grid, estimate.start_error),
        )

    def rollout(
        self, now: float, estimate: Estimate, parameters: np.ndarray, jacobian: bool = False
    ):
        """The reduced model's run over one horizon from the estimate under a plan.

        The solver's own RK4 map, forecast and clearance error
        (:class:`~cable_ocp.control.linearisation.ErrorLinearisation`): a
        :class:`~cable_ocp.control.linearisation.Linearised` whose ``error`` (m, with the bias)
        is at the problem's grid (``problem.grid``, s from ``now``), with its Jacobian in the
        plan's parameters where ``jacobian`` (a sensitivity sweep, as a solve's; else a run
        alone, a fraction of its cost). None when the solver has no such map (IPOPT's multiple
        shooting).
        """
        linearisation = getattr(self.solver, "linearisation", None)
        if linearisation is None:
            return None
        values = self.parameter_values(now, estimate)
        if jacobian:
            return linearisation(values, parameters)
        return linearisation.error(values, parameters)

    def infeasible(self, status: str) -> bool:
        """Whether a failed solve's status says that its QP had no feasible point.

        The registry says which text (:attr:`~cable_ocp.control.solvers.Solver.infeasible`).
        """
        marker = self.entry.infeasible
        return marker is not None and marker in status

    def outside(self, now) -> str:
        """Why the controller cannot solve at ``now`` (s); empty when it can."""
        end = self.scene.numerics.duration
        if isinstance(now, bool) or not isinstance(now, int | float | np.number):
            return f"now = {now!r:.40}: not a time (s); nothing solved"
        if not np.isfinite(now) or now < self.plan_start or now >= end:
            return (
                f"now = {now!r} s is outside [{self.plan_start:g}, {end:g}) s (from the plan in "
                "force to the scene's numerics.duration): nothing left to control; not solved"
            )
        return ""

    def make_step(self, now: float, estimate: Estimate, angle: float, rate: float) -> Solve:
        """Solve at the sample ``now`` with the plan starting at the winch's ``angle``, ``rate``.

        The guess is the plan in force moved on to ``now`` (a failed solve leaves that plan in
        force, as the loop does). A ``now`` outside the scene's time, from the plan in force's
        start up to ``numerics.duration``, is a failed solve that says so; an ``estimate`` of
        another kind (None, say) a ValueError naming it.
        """
        if not isinstance(estimate, Estimate):
            raise ValueError(
                f"estimate = {estimate!r:.60}: expected the Estimate that Estimator.make_step "
                "returned"
            )
        outside = self.outside(now)
        if outside:
            return Solve(self.plan, outside, False, 0, 0.0)
        values = self.parameter_values(now, estimate)
        guess = self.control.resampled(self.plan, now - self.plan_start)
        fixed = {self._start_angle: angle, self._start_rate: rate}
        lower, upper = self.problem.bounds.narrowed(estimate.margin, self.settings.sample)
        outcome = self.solver.solve(values, guess, fixed, lower, upper)
        if not outcome.success and estimate.margin > 0 and self.infeasible(outcome.status):
            # The room for the heave feedback grew since the plan in force was solved, faster
            # than the winch's rate and acceleration limits let the plan move out of it (seed
            # 2, case 7 of the whole-space benchmark: 35 of 458 solves in Hs 2.1 m): solve on
            # the winch's own range, which the plan in force met, and say so.
            first = outcome.solve_time
            lower, upper = self.problem.bounds.narrowed(0.0, self.settings.sample)
            outcome = self.solver.solve(values, guess, fixed, lower, upper)
            outcome = replace(outcome, solve_time=first + outcome.solve_time)
            if outcome.success:
                outcome = replace(outcome, status=f"{outcome.status} ({WIDENED})")
        if outcome.success:
            self.plan, self.plan_start = outcome.parameters, now
        return Solve(
            parameters=outcome.parameters,
            status=outcome.status,
            success=outcome.success,
            iterations=outcome.iterations,
            solve_time=outcome.solve_time,
        )
