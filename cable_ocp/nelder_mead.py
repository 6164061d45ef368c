"""The paper's method: Nelder-Mead over the spline knots, one RK4 run per evaluation.

The winch bounds (angle, and ``winch.rate_max`` / ``winch.acceleration_max`` when set) are held on
the whole spline, between the knots too, by the linear constraints of :mod:`cable_ocp.bounds`: a
profile that breaks them is not simulated but scored worse than any run (an extreme barrier that
grows with the violation, so the simplex is pushed back), and the search starts from a profile
that keeps them. The returned profile is checked again; a violation makes the search a failure.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize

from cable_ocp import winch
from cable_ocp.bounds import LinearBounds, angle_bounds, violation
from cable_ocp.controls import KnotSpline
from cable_ocp.drive import Drive
from cable_ocp.integrate import SimulationError, integrate, step_count
from cable_ocp.model import CableModel
from cable_ocp.ocp import GUESS_TOLERANCE, initial_parameters
from cable_ocp.progress import Progress
from cable_ocp.seabed import clearance_error, rms_objective
from cable_ocp.statics import equilibrium

# Objective given to Nelder-Mead for a winch whose simulation fails (m): worse than any real run.
FAILED_RUN_OBJECTIVE = 1e3
# Objective for a winch that breaks its bounds (m): this plus FAILED_RUN_OBJECTIVE per unit of the
# largest violation (rad, rad/s or rad/s^2), worse than a failed run.
INFEASIBLE_OBJECTIVE = 2 * FAILED_RUN_OBJECTIVE


@dataclass(frozen=True)
class NelderMeadSettings:
    """Settings of the Nelder-Mead search.

    Attributes
    ----------
    elements : int or None
        Elements of the model each evaluation simulates (None: the scene's).
    step : float or None, s
        RK4 step of the evaluations (None: the scene's).
    max_evaluations : int
    xatol : float, rad
    fatol : float, m
    compiled : bool
        Simulate with the RK4 step compiled to C (cached on disk).
    """

    elements: int | None = None
    step: float | None = None
    max_evaluations: int = 3000
    xatol: float = 1e-3
    fatol: float = 1e-5
    compiled: bool = True

    def __post_init__(self):
        if self.max_evaluations < 1:
            raise ValueError(f"max_evaluations = {self.max_evaluations}: must be >= 1")
        if self.elements is not None and self.elements < 1:
            raise ValueError(f"elements = {self.elements}: must be >= 1")
        if self.step is not None and self.step <= 0:
            raise ValueError(f"step = {self.step}: must be > 0 s")


@dataclass(frozen=True)
class NelderMeadOutcome:
    """What the search returned (before verification on the full model).

    Attributes
    ----------
    parameters : array (knots,), rad
    control : KnotSpline
    success : bool
    message : str
    evaluations : int
    iterations : int
    objective : float, m
        Omega on the evaluation model.
    solve_time : float, s
    history : list of float
        Best Omega after each evaluation, m.
    """

    parameters: np.ndarray
    control: KnotSpline
    success: bool
    message: str
    evaluations: int
    iterations: int
    objective: float
    solve_time: float
    history: list[float]


def solve_nelder_mead(
    scene, settings: NelderMeadSettings, quiet: bool = False
) -> NelderMeadOutcome:
    """Minimise Omega over the spline knots with SciPy's bounded Nelder-Mead.

    ``success`` is False, with the reason in ``message``, when SciPy reports a failure (e.g. the
    evaluation limit), when no evaluated profile both kept the winch bounds and simulated, or when
    the returned profile breaks a bound by more than :data:`cable_ocp.bounds.BOUND_TOLERANCE`.
    """
    started = time.perf_counter()
    duration = scene.numerics.duration
    step = settings.step or scene.numerics.step
    control = KnotSpline(duration, scene.winch.knots)
    low, high = angle_bounds(scene, scene.segment_length)
    model = CableModel.from_scene(scene, settings.elements)
    n = model.spec.elements
    locked = Drive.from_scene(scene, winch.locked, elements=n)
    x0 = equilibrium(model, locked)
    hills = scene.seabed.hills
    compiled = settings.compiled

    grid = np.arange(step_count(duration, step) + 1) * step
    constraints = LinearBounds.build(scene, control, grid)

    def omega(parameters: np.ndarray) -> float:
        excess = constraints.excess(parameters)
        if excess > 0:
            return INFEASIBLE_OBJECTIVE + FAILED_RUN_OBJECTIVE * excess
        drive = Drive.from_scene(scene, control.angle_function(parameters), elements=n)
        try:
            run = integrate(
                model, x0, drive, duration, step, tolerance=GUESS_TOLERANCE, compiled=compiled
            )
        except SimulationError:
            return FAILED_RUN_OBJECTIVE
        return rms_objective(run.time, clearance_error(hills, run.states[:, :3]))

    locked_run = integrate(
        model, x0, locked, duration, step, tolerance=GUESS_TOLERANCE, compiled=compiled
    )
    rise = clearance_error(hills, locked_run.states[:, :3])
    guess = np.clip(initial_parameters(scene, control, locked_run.time, rise, low, high), low, high)
    guess = constraints.scale_into(guess)

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
        bounds=[(low, high)] * control.size,
        options={
            "maxfev": settings.max_evaluations,
            "xatol": settings.xatol,
            "fatol": settings.fatol,
            "adaptive": True,
        },
    )
    progress.close()
    parameters = np.asarray(result.x)
    success, message = bool(result.success), str(result.message)
    reason = violation(scene, control, parameters)
    if reason is not None:
        success, message = False, f"no profile within the winch bounds found: {reason}"
    elif result.fun >= FAILED_RUN_OBJECTIVE:
        success, message = False, "no winch profile with a successful simulation found"
    return NelderMeadOutcome(
        parameters=parameters,
        control=control,
        success=success,
        message=message,
        evaluations=int(result.nfev),
        iterations=int(result.nit),
        objective=float(result.fun),
        solve_time=time.perf_counter() - started,
        history=history,
    )
