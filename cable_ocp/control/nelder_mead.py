"""The paper's method: Nelder-Mead over the spline knots, one RK4 run per evaluation.

The winch bounds (angle, and ``winch.rate_max`` / ``winch.acceleration_max`` when set) are held on
the whole spline, between the knots too, by the linear constraints of :mod:`cable_ocp.drive.bounds`:
a profile that breaks them is not simulated but scored worse than any run (an extreme barrier that
grows with the violation, so the simplex is pushed back), and the search starts from a profile
that keeps them. The returned profile is checked again; a violation makes the search a failure.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np
from scipy.optimize import minimize

from cable_ocp.control import defaults
from cable_ocp.control.checks import Rule, check_fields
from cable_ocp.control.linearisation import compile_rhs_jacobian_in_background
from cable_ocp.control.problem import ProblemSolver, SolverOutcome, WinchProblem
from cable_ocp.control.settings import ModelSettings, OcpSettings
from cable_ocp.drive.bounds import violation
from cable_ocp.drive.controls import KnotSpline
from cable_ocp.model.cable import CableModel
from cable_ocp.simulation.integrate import SimulationError
from cable_ocp.simulation.progress import Progress

# Objective given to Nelder-Mead for a winch whose simulation fails (m): worse than any real run.
FAILED_RUN_OBJECTIVE = 1e3
# Objective for a winch that breaks its bounds (m): this plus FAILED_RUN_OBJECTIVE per unit of the
# largest violation (rad, rad/s or rad/s^2), worse than a failed run.
INFEASIBLE_OBJECTIVE = 2 * FAILED_RUN_OBJECTIVE


@dataclass(frozen=True)
class NelderMeadSettings:
    """Settings of the Nelder-Mead search (its model and step are ``ModelSettings``).

    Attributes
    ----------
    max_evaluations : int
        Objective evaluations (one RK4 run of the model each) before the search stops unfinished
        (SciPy's ``maxfev``; the paper's method usually stops here).
    xatol : float, rad
        The simplex has converged once its vertices are this close in every knot value...
    fatol : float, m
        ... and their Omega this close (SciPy's ``xatol`` and ``fatol``, both must hold).
    """

    max_evaluations: int = 3000
    xatol: float = 1e-3
    fatol: float = 1e-5

    def __post_init__(self):
        check_fields(
            self,
            {
                "max_evaluations": Rule("integer", low=1),
                "xatol": Rule("number", above=0, unit="rad"),
                "fatol": Rule("number", above=0, unit="m"),
            },
        )


def resolved_nelder_mead(scene, settings: OcpSettings, compiled: bool | None = None):
    """The settings with the elements and step left unset derived from the scene, and how.

    As :func:`cable_ocp.control.shooting.resolved`, the step a whole fraction of the duration. The
    paper's method takes the spline through the scene's knots, and no shooting intervals.
    """
    if settings.control != "spline" or settings.intervals is not None:
        raise ValueError(
            "grid: Nelder-Mead searches the spline through winch.knots of the scene; leave "
            "GridSettings.control and intervals unset (or take a shooting solver)"
        )
    compiled = settings.compiled if compiled is None else compiled
    elements, notes = defaults.model_elements(scene, settings.elements)
    open_loop, _ = WinchProblem.open_loop_scene(scene)
    step, derived = defaults.model_step(
        open_loop, elements, settings.step, scene.numerics.duration, defaults.STEP_CAP, compiled,
        "step",
    )  # fmt: skip
    notes += derived
    text = "derived settings: " + ", ".join(notes) if notes else ""
    return replace(settings, model=ModelSettings(elements, step)), text


def nelder_mead_problem(scene, settings: OcpSettings, jacobian: bool = False) -> WinchProblem:
    """The scene's problem as the paper states it: the winch angle a spline through its knots.

    ``jacobian``: start compiling the model's Jacobian ahead, for a solver that needs it (the
    search itself takes no derivatives).
    """
    if jacobian and settings.compiled:
        compile_rhs_jacobian_in_background(CableModel.from_scene(scene, settings.elements))
    control = KnotSpline(scene.numerics.duration, scene.winch.knots)
    return WinchProblem.from_scene(scene, control, settings.elements, settings.step)


class NelderMead(ProblemSolver):
    """SciPy's bounded Nelder-Mead on a winch problem (in :mod:`cable_ocp.control.solvers`).

    Parameters
    ----------
    problem : WinchProblem
        Its control the spline through the scene's knots.
    settings : NelderMeadSettings
    compiled : bool
        Simulate with the RK4 step compiled to C (cached on disk).
    quiet : bool
        No progress bar.
    """

    def __init__(
        self,
        problem: WinchProblem,
        settings: NelderMeadSettings,
        compiled: bool = True,
        quiet: bool = False,
    ):
        self.problem, self.settings, self.compiled, self.quiet = problem, settings, compiled, quiet

    def run(self, values, guess, fixed, lower, upper) -> SolverOutcome:
        """Minimise Omega over the knots from ``guess`` (rad), moved into the winch bounds.

        The search takes the problem's own parameter values only (the open loop's, with no
        model-correction bias; a landing's reference is the problem's own) and no fixed
        parameters or narrowed bounds: it is the paper's open-loop method, not a closed loop's
        solver. ``success`` is False, with the reason in ``status``, when SciPy reports a
        failure (e.g. the evaluation limit), when no evaluated profile both kept the winch bounds
        and simulated, or when the returned profile breaks a bound by more than
        :data:`cable_ocp.drive.bounds.BOUND_TOLERANCE`.
        """
        # The problem's own bias is a landing's reference (zero elsewhere), which its Omega has.
        own = self.problem.parameter_values().bias
        if fixed or lower is not None or upper is not None or np.any(values.bias != own):
            raise ValueError(
                "Nelder-Mead solves the open-loop problem only: no fixed parameters, narrowed "
                "bounds or model-correction bias"
            )
        return _search(self.problem, self.settings, self.compiled, self.quiet, guess)


def _search(
    problem: WinchProblem,
    settings: NelderMeadSettings,
    compiled: bool,
    quiet: bool,
    start: np.ndarray,
) -> SolverOutcome:
    """The bounded search of :meth:`NelderMead.solve` from ``start``."""
    started = time.perf_counter()
    constraints, low, high = problem.bounds, problem.low, problem.high

    def omega(parameters: np.ndarray) -> float:
        excess = constraints.excess(parameters)
        if excess > 0:
            return INFEASIBLE_OBJECTIVE + FAILED_RUN_OBJECTIVE * excess
        try:
            return problem.omega(problem.simulate(parameters, compiled=compiled))
        except SimulationError:
            return FAILED_RUN_OBJECTIVE

    guess = constraints.scale_into(np.clip(start, low, high))
    history: list[float] = []
    progress = Progress("nelder-mead", settings.max_evaluations, quiet)

    def tracked(parameters: np.ndarray) -> float:
        value = omega(parameters)
        history.append(min(value, history[-1]) if history else value)
        progress.update(len(history), f"Omega = {history[-1]:.4f} m")
        return value

    result = minimize(
        tracked,
        guess,
        method="Nelder-Mead",
        bounds=[(low, high)] * problem.control.size,
        options={
            "maxfev": settings.max_evaluations,
            "xatol": settings.xatol,
            "fatol": settings.fatol,
            "adaptive": True,
        },
    )
    progress.close()
    parameters = np.asarray(result.x)
    success, status = bool(result.success), str(result.message)
    reason = violation(problem.scene, problem.control, parameters)
    if reason is not None:
        success, status = False, f"no profile within the winch bounds found: {reason}"
    elif result.fun >= FAILED_RUN_OBJECTIVE:
        success, status = False, "no winch profile with a successful simulation found"
    solve_time = time.perf_counter() - started
    return SolverOutcome(
        parameters=parameters,
        status=status,
        success=success,
        iterations=int(result.nit),
        evaluations=int(result.nfev),
        omega=float(result.fun),
        build_time=0.0,
        compile_time=0.0,
        solve_time=solve_time,
        function_time=solve_time,
        history=history,
    )
