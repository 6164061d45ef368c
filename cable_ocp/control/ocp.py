"""Optimal winch control by direct shooting and IPOPT (CONVENTIONS.md §5, paper §5).

The horizon ``[0, T]`` is cut into intervals, each a fold of RK4 steps of the (possibly reduced)
model. With single shooting (the default) the intervals are chained from the initial state and
the winch parameters are the only decision variables: the objective's gradient is one reverse
sweep through the RK4 steps. With multiple shooting the state at every node is a decision
variable too and continuity constraints join the intervals: its constraint Jacobian needs one
forward sweep per state and parameter colour (about 45 at n = 3), so it costs far more per
iteration, for more robustness on strongly nonlinear problems. The winch angle is linear in its
parameters (:mod:`cable_ocp.drive.controls`), so the angle, rate, acceleration and top-element
length bounds are linear constraints; they hold between the RK4 samples too
(:mod:`cable_ocp.drive.bounds`), within :data:`cable_ocp.drive.bounds.BOUND_TOLERANCE`. The
objective is ``Omega^2`` of eq. 39 by the trapezoidal rule over the RK4 steps.
"""

from __future__ import annotations

import signal
import threading
import time
from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from cable_ocp.control.problem import SolverOutcome, WinchProblem
from cable_ocp.drive.controls import HermiteIntervals, KnotSpline
from cable_ocp.drive.drive import stage_times
from cable_ocp.model.cable import CableModel
from cable_ocp.model.compile import CompileReport
from cable_ocp.model.layout import INPUT_SIZE, INPUTS
from cable_ocp.simulation.integrate import (
    SimulationError,
    stage_inputs,
    step_compile_report,
    step_count,
    step_function,
)
from cable_ocp.simulation.progress import IterationLog, check_verbosity
from cable_ocp.simulation.seabed import clearance_reference, seabed_height, trapezoid_weights

NLP_FUNCTIONS = ("nlp_f", "nlp_g", "nlp_grad_f", "nlp_jac_g", "nlp_hess_l", "nlp_grad")
# IPOPT's status when CasADi's interrupt check stopped it.
INTERRUPTED = "User_Requested_Stop"


def interrupted_solve(solver: ca.Function, **arguments) -> dict:
    """``solver(**arguments)``, re-raising a user's Ctrl-C as KeyboardInterrupt.

    IPOPT turns an interrupt into a return status (``User_Requested_Stop``, or
    ``NonIpopt_Exception_Thrown`` when CasADi's check or a Python callback met the
    KeyboardInterrupt); a user's interrupt is never a solver's failure, so a SIGINT seen during
    the solve leaves here as the interrupt it was. The handler is only watched from the main
    thread (a Dask worker's solve cannot be interrupted this way anyway).
    """
    seen = []
    previous = signal.getsignal(signal.SIGINT)
    watched = threading.current_thread() is threading.main_thread() and callable(previous)

    def watch(number, frame):
        seen.append(number)
        previous(number, frame)

    if watched:
        signal.signal(signal.SIGINT, watch)
    try:
        solution = solver(**arguments)
    except RuntimeError:
        if seen:
            raise KeyboardInterrupt from None
        raise
    finally:
        if watched:
            signal.signal(signal.SIGINT, previous)
    if seen or solver.stats()["return_status"] == INTERRUPTED:
        raise KeyboardInterrupt
    return solution


@dataclass(frozen=True)
class IpoptSettings:
    """How the shooting NLP is built and solved.

    Attributes
    ----------
    elements : int or None
        Elements of the optimisation model (None: the scene's). Fewer elements make a cheaper
        model; Omega is always verified on the scene's own model.
    step : float or None, s
        RK4 step inside the intervals (None: the scene's step).
    shooting : str
        ``"single"`` (only the winch parameters are variables) or ``"multiple"`` (the states at
        the interval ends too, joined by continuity constraints).
    intervals : int
        Shooting intervals; the number of RK4 steps must be a multiple of it. With single
        shooting they only cut the chain of RK4 steps (and set the Hermite control's intervals).
    control : str
        ``"hermite"`` (piecewise cubic per control interval) or ``"spline"`` (the paper's knots).
    control_intervals : int or None
        Intervals of the Hermite control (None: as many as shooting intervals).
    hessian : str
        ``"limited-memory"`` (L-BFGS) or ``"exact"``.
    max_iter : int
    tolerance : float
        IPOPT's ``tol``.
    threads : int
        Shooting intervals evaluated in parallel (multiple shooting only).
    compiled : bool
        Compile the model's right-hand side and its first derivatives to C (cached on disk,
        one library per model structure), and verify on the compiled full model.
    ipopt_options : dict
        Further IPOPT options, passed as they are.
    """

    elements: int | None = None
    step: float | None = None
    shooting: str = "single"
    intervals: int = 42
    control: str = "hermite"
    control_intervals: int | None = None
    hessian: str = "limited-memory"
    max_iter: int = 300
    tolerance: float = 1e-8
    threads: int = 1
    compiled: bool = True
    ipopt_options: dict = field(default_factory=dict)

    def __post_init__(self):
        if self.shooting not in ("single", "multiple"):
            raise ValueError(f"shooting = {self.shooting!r}: must be 'single' or 'multiple'")
        if self.control not in ("hermite", "spline"):
            raise ValueError(f"control = {self.control!r}: must be 'hermite' or 'spline'")
        if self.hessian not in ("limited-memory", "exact"):
            raise ValueError(f"hessian = {self.hessian!r}: must be 'limited-memory' or 'exact'")
        for name in ("intervals", "max_iter", "threads"):
            if getattr(self, name) < 1:
                raise ValueError(f"{name} = {getattr(self, name)}: must be >= 1")
        if self.elements is not None and self.elements < 1:
            raise ValueError(f"elements = {self.elements}: must be >= 1")
        if self.step is not None and self.step <= 0:
            raise ValueError(f"step = {self.step}: must be > 0 s")
        if self.hessian == "exact" and self.compiled:
            raise ValueError(
                "hessian = 'exact' needs second derivatives, which the compiled step does not "
                "carry: set compiled=False (interpreted) or hessian='limited-memory'"
            )


def ipopt_options(
    hessian: str, max_iter: int, tolerance: float, verbose: bool = False, extra: dict | None = None
) -> dict:
    """IPOPT's options for an Omega^2 objective (the open and the closed loop alike).

    Parameters
    ----------
    hessian : str
        ``"limited-memory"`` or ``"exact"``.
    max_iter : int
    tolerance : float
        IPOPT's ``tol``.
    verbose : bool
        IPOPT's own log.
    extra : dict, optional
        Further options, passed as they are (they win).
    """
    return {
        "hessian_approximation": hessian,
        "max_iter": max_iter,
        "tol": tolerance,
        "print_level": 5 if verbose else 0,
        "sb": "no" if verbose else "yes",
        # Omega^2 in units of (1 cm)^2, so IPOPT's tolerances mean something in metres.
        "obj_scaling_factor": 1e4,
        # Stop once Omega^2 changes by less than 0.1 % over 5 acceptable iterations.
        "acceptable_tol": 1e-4,
        "acceptable_iter": 5,
        "acceptable_obj_change_tol": 1e-3,
        **(extra or {}),
    }


def make_control(scene, settings: IpoptSettings) -> KnotSpline | HermiteIntervals:
    """The control parametrisation the settings ask for."""
    duration = scene.numerics.duration
    if settings.control == "spline":
        return KnotSpline(duration, scene.winch.knots)
    return HermiteIntervals(duration, settings.control_intervals or settings.intervals)


def steps_per_interval(duration: float, step: float, intervals: int) -> int:
    """RK4 steps in each shooting interval; ``intervals`` must divide the steps of the run."""
    total_steps = step_count(duration, step)
    if total_steps % intervals:
        raise ValueError(
            f"intervals = {intervals} must divide the {total_steps} RK4 steps "
            f"(T = {duration} s, h = {step} s)"
        )
    return total_steps // intervals


def ipopt_problem(scene, settings: IpoptSettings) -> WinchProblem:
    """The scene's winch problem with the control, model and step the IPOPT settings ask for.

    The shooting intervals are checked first, before any model is built.
    """
    step = settings.step or scene.numerics.step
    steps_per_interval(scene.numerics.duration, step, settings.intervals)
    return WinchProblem.from_scene(
        scene, make_control(scene, settings), settings.elements, settings.step
    )


def ocp_step(
    model: CableModel, step: float, compiled: bool
) -> tuple[ca.Function, CompileReport | None]:
    """The RK4 step ``(x, stage_inputs) -> x_next`` with first derivatives, for the NLP.

    Compiled, the step of :func:`cable_ocp.simulation.integrate.step_function` with its
    derivatives; interpreted, the model's SX step (second derivatives too). The report is None
    when nothing was compiled.
    """
    if not compiled:
        return step_function(model, step), None
    function = step_function(model, step, compiled=True, derivatives=True)
    return function, step_compile_report(model, step, derivatives=True)


def _interval_function(step_function, step, steps, hills, reference) -> ca.Function:
    """``(x, stage inputs, bias) -> (x_end, integral of (e + bias)^2)`` over one interval.

    ``bias`` (1 x steps+1) is added to the clearance error at the RK4 points: the correction that
    makes a reduced model reproduce the full model's error (see :class:`ShootingProblem`).
    """
    size = step_function.size1_in(0)
    x = ca.MX.sym("x", size)
    stages = ca.MX.sym("stages", 15, 3 * steps)
    bias = ca.MX.sym("bias", 1, steps + 1)
    states = step_function.mapaccum(steps)(x, stages)
    points = ca.horzcat(x, states)
    xe = ca.SX.sym("xe", size)
    error = xe[2] - seabed_height(hills, xe[0], xe[1]) - reference
    errors = ca.Function("e", [xe], [error]).map(steps + 1)(points) + bias
    cost = ca.mtimes(errors**2, ca.DM(trapezoid_weights(step, steps + 1)))
    return ca.Function("interval", [x, stages, bias], [states[:, -1], cost])


class ShootingProblem:
    """The shooting NLP of a scene, built once and solved as often as needed.

    The NLP has a parameter, the bias ``b(t)`` on the RK4 grid, added to the clearance error:
    ``Omega^2 = 1/T int (e(t) + b(t))^2 dt``. With ``b = 0`` it is the plain problem; the front door
    sets ``b = e_full - e_reduced`` to correct a reduced model by the full one.

    Parameters
    ----------
    problem : WinchProblem
    settings : IpoptSettings
    quiet : bool
        Print nothing.
    verbose : bool
        Print IPOPT's own log and timing table instead of one progress line per iteration.
    """

    def __init__(
        self,
        problem: WinchProblem,
        settings: IpoptSettings,
        quiet: bool = False,
        verbose: bool = False,
    ):
        check_verbosity(quiet, verbose)
        started = time.perf_counter()
        self.problem, self.settings = problem, settings
        duration, step = problem.duration, problem.step
        model, control = problem.model, problem.control
        self.per_interval = per_interval = steps_per_interval(duration, step, settings.intervals)
        total_steps = per_interval * settings.intervals

        step_times = problem.grid[:-1]
        fixed = stage_inputs(problem.drive, step_times, step)
        times, left = stage_times(step_times, step)
        parameters = ca.MX.sym("winch", control.size)
        radius = problem.scene.winch.drum_radius
        winch_rows = ca.vertcat(
            *[(radius * ca.sparsify(ca.DM(b)) @ parameters).T for b in control.basis(times, left)]
        )
        # The winch sets the top-element length with its rate and acceleration (three rows).
        winch_inputs = ca.MX.zeros(INPUT_SIZE, fixed.shape[1])
        winch_inputs[INPUTS.top_length : INPUTS.top_length_acceleration + 1, :] = winch_rows
        inputs = ca.DM(fixed) + winch_inputs
        bias = ca.MX.sym("bias", total_steps + 1)
        bias_rows = ca.horzcat(
            *[
                bias[k * per_interval : (k + 1) * per_interval + 1].T
                for k in range(settings.intervals)
            ]
        )
        step_function, report = ocp_step(model, step, settings.compiled)
        self.compile_time = report.compile_time if report is not None else 0.0
        interval = _interval_function(
            step_function,
            step,
            per_interval,
            problem.scene.seabed.hills,
            clearance_reference(problem.scene.seabed.hills, problem.x0),
        )
        if settings.shooting == "single":
            costs = interval.mapaccum(settings.intervals)(ca.DM(problem.x0), inputs, bias_rows)[1]
            nodes, continuity = ca.MX(model.state_size, 0), ca.MX(0, 1)
        else:
            nodes = ca.MX.sym("nodes", model.state_size, settings.intervals)
            starts = ca.horzcat(ca.DM(problem.x0), nodes[:, :-1])
            mapped = interval.map(settings.intervals, "thread", settings.threads)
            ends, costs = mapped(starts, inputs, bias_rows)
            continuity = ca.vec(ends - nodes)
        objective = ca.sum2(costs) / duration

        bounds = problem.bounds
        variables = ca.vertcat(ca.vec(nodes), parameters) if nodes.numel() else parameters
        constraints = ca.densify(
            ca.vertcat(continuity, ca.sparsify(ca.DM(bounds.matrix)) @ parameters)
        )
        self.lbg = np.concatenate([np.zeros(continuity.numel()), bounds.lower])
        self.ubg = np.concatenate([np.zeros(continuity.numel()), bounds.upper])
        self.history: list[float] = []
        self.log = IterationLog("ipopt", quiet=quiet or verbose)
        self._callback = _History(self.history, self.log, self.lbg, self.ubg)
        options = {
            "ipopt": ipopt_options(
                settings.hessian,
                settings.max_iter,
                settings.tolerance,
                verbose,
                settings.ipopt_options,
            ),
            "print_time": verbose,
            "iteration_callback": self._callback,
        }
        self.solver = ca.nlpsol(
            "winch_ocp",
            "ipopt",
            {"x": variables, "f": objective, "g": constraints, "p": bias},
            options,
        )
        self.build_time = time.perf_counter() - started

    def solve(self, parameters: np.ndarray, bias: np.ndarray | None = None) -> SolverOutcome:
        """Solve from the forward run of ``parameters`` with the given bias (m, on the grid).

        The forward runs are interpreted: a reduced model's run is short, and a compiled one
        would need a library of its own (without derivatives).
        """
        problem = self.problem
        try:
            states = problem.simulate(parameters)
        except SimulationError:
            parameters = np.zeros(problem.control.size)
            states = problem.simulate(parameters)
        nodes = states[self.per_interval :: self.per_interval].T
        if self.settings.shooting == "single":
            nodes = nodes[:, :0]
        bias = np.zeros(problem.grid.size) if bias is None else bias
        self.history.clear()
        self.log.restart()
        started = time.perf_counter()
        solution = interrupted_solve(
            self.solver,
            x0=np.concatenate([nodes.ravel(order="F"), parameters]),
            lbg=self.lbg,
            ubg=self.ubg,
            p=bias,
        )
        solve_time = time.perf_counter() - started
        stats = self.solver.stats()
        iterations = int(stats["iter_count"])
        return SolverOutcome(
            parameters=np.array(solution["x"][-problem.control.size :]).ravel(),
            status=stats["return_status"],
            success=bool(stats["success"]),
            iterations=iterations,
            evaluations=iterations + 1,
            omega=float(np.sqrt(max(float(solution["f"]), 0.0))),
            build_time=self.build_time,
            compile_time=self.compile_time,
            solve_time=solve_time,
            function_time=sum(stats.get(f"t_wall_{name}", 0.0) for name in NLP_FUNCTIONS),
            history=list(self.history),
        )


class _History(ca.Callback):
    """Records the objective at every IPOPT iteration and reports it to an :class:`IterationLog`.

    The constraint violation reported is the largest of the continuity residual and the excess
    over the winch bounds (in the constraint's own unit: m, rad, rad/s or rad/s^2).
    """

    def __init__(self, history: list[float], log: IterationLog, lbg, ubg):
        ca.Callback.__init__(self)
        self.history, self.log, self.lbg, self.ubg = history, log, lbg, ubg
        self.construct("history", {})

    def get_n_in(self):
        return ca.nlpsol_n_out()

    def get_n_out(self):
        return 1

    def get_name_in(self, i):
        return ca.nlpsol_out(i)

    def get_name_out(self, i):
        return "ret"

    def get_sparsity_in(self, i):
        name = ca.nlpsol_out(i)
        if name == "f":
            return ca.Sparsity.scalar()
        if name in ("g", "lam_g"):
            return ca.Sparsity.dense(self.lbg.size)
        return ca.Sparsity(0, 0)

    def eval(self, arg):
        objective = float(arg[ca.nlpsol_out().index("f")])
        g = np.array(arg[ca.nlpsol_out().index("g")]).ravel()
        violation = float(max(np.max(self.lbg - g), np.max(g - self.ubg), 0.0))
        self.history.append(objective)
        self.log.line(len(self.history) - 1, np.sqrt(max(objective, 0.0)), violation)
        return [0]
