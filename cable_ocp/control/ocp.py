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

import time
from dataclasses import dataclass, field, replace

import casadi as ca
import numpy as np

from cable_ocp.control import defaults
from cable_ocp.control.checks import Rule, check_fields, check_ipopt_options
from cable_ocp.control.gauss_newton import CLEARANCE_BACKOFF
from cable_ocp.control.interrupts import keeping_interrupts
from cable_ocp.control.linearisation import (
    clearance_error_function,
    compile_rhs_jacobian_in_background,
)
from cable_ocp.control.parameters import symbols
from cable_ocp.control.problem import ProblemSolver, SolverOutcome, WinchProblem
from cable_ocp.control.settings import ModelSettings, OcpSettings
from cable_ocp.drive.controls import HermiteIntervals, KnotSpline
from cable_ocp.drive.drive import stage_times
from cable_ocp.model import structured
from cable_ocp.model.cable import CableModel
from cable_ocp.model.compile import CompileReport
from cable_ocp.model.layout import INPUT_SIZE
from cable_ocp.scene.records import control_size
from cable_ocp.simulation.budget import check_memory, optimisation_memory
from cable_ocp.simulation.integrate import step_compile_report, step_function
from cable_ocp.simulation.progress import IterationLog, check_verbosity
from cable_ocp.simulation.seabed import trapezoid_weights

NLP_FUNCTIONS = ("nlp_f", "nlp_g", "nlp_grad_f", "nlp_jac_g", "nlp_hess_l", "nlp_grad")
# IPOPT's status when CasADi's interrupt check stopped it.
INTERRUPTED = "User_Requested_Stop"


def interrupted_solve(solver: ca.Function, **arguments) -> dict:
    """``solver(**arguments)``, re-raising a user's Ctrl-C as KeyboardInterrupt.

    A user's interrupt is never a solver's failure (:mod:`cable_ocp.control.interrupts`); IPOPT's
    ``User_Requested_Stop`` is one too.
    """
    with keeping_interrupts():
        solution = solver(**arguments)
    if solver.stats()["return_status"] == INTERRUPTED:
        raise KeyboardInterrupt
    return solution


@dataclass(frozen=True)
class IpoptSettings:
    """IPOPT's own settings (the model's, grid's and transcription's are apart).

    The others are :mod:`cable_ocp.control.settings`'.

    Attributes
    ----------
    hessian : str
        IPOPT's Hessian: ``"limited-memory"`` (L-BFGS) or ``"exact"`` (second derivatives, which
        the compiled step does not carry: ``TranscriptionSettings(compiled=False)``).
    max_iter : int
    tolerance : float
        IPOPT's ``tol``.
    ipopt_options : dict
        Further IPOPT options, passed as they are (checked by IPOPT before any solve).
    """

    hessian: str = "limited-memory"
    max_iter: int = 300
    tolerance: float = 1e-8
    ipopt_options: dict = field(default_factory=dict)

    def __post_init__(self):
        check_fields(
            self,
            {
                "hessian": Rule("choice", choices=("limited-memory", "exact")),
                "max_iter": Rule("integer", low=1),
                "tolerance": Rule("number", above=0),
                "ipopt_options": Rule("table"),
            },
        )


def check_ipopt(settings: OcpSettings) -> None:
    """What IPOPT's settings must agree on with the transcription, and its own options.

    ValueError naming the misfit, before any work: an exact Hessian needs second derivatives,
    which the compiled step does not carry; options IPOPT does not take.
    """
    ipopt = settings.solver_settings
    if ipopt.hessian == "exact" and settings.compiled:
        raise ValueError(
            "IpoptSettings.hessian = 'exact' needs second derivatives, which the compiled step "
            "does not carry: set TranscriptionSettings(compiled=False) or "
            "hessian='limited-memory'"
        )
    check_ipopt_options(ipopt.ipopt_options)


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


def make_control(scene, settings: OcpSettings) -> KnotSpline | HermiteIntervals:
    """The control parametrisation the settings ask for."""
    duration = scene.numerics.duration
    if settings.control == "spline":
        return KnotSpline(duration, scene.winch.knots)
    return HermiteIntervals(duration, settings.control_intervals)


def control_of(label: str, duration: float) -> KnotSpline | HermiteIntervals:
    """The control a result names (``"hermite(84)"``, ``"spline(14)"``) over ``duration`` (s)."""
    size = control_size(label)
    if label.startswith("spline"):
        return KnotSpline(duration, size)
    return HermiteIntervals(duration, size // 2)


def full_model_scene(scene, settings: OcpSettings):
    """The scene that the full model's runs take under resolved settings, and what changed.

    Its step is shortened where the Hermite nodes would fall inside the scene's steps
    (:func:`cable_ocp.control.defaults.on_nodes`); a spline (C2) needs no such fit.

    Returns
    -------
    (Scene, str)
    """
    if settings.control == "spline":
        return scene, ""
    return defaults.on_nodes(scene, settings.control_intervals)


def steps_per_interval(duration: float, step: float, intervals: int) -> int:
    """RK4 steps in each shooting interval; ``intervals`` must divide the steps of the run."""
    total_steps = round(duration / step)
    if total_steps < 1 or abs(total_steps * step - duration) > 1e-9 * max(duration, 1.0):
        raise ValueError(
            f"step = {step:g} s (of the optimisation model) must divide numerics.duration = "
            f"{duration:g} s into whole RK4 steps: leave step unset to derive it"
        )
    if total_steps % intervals:
        raise ValueError(
            f"intervals = {intervals} must divide the {total_steps} RK4 steps "
            f"(T = {duration:g} s, step = {step:g} s): leave intervals or step unset to derive it"
        )
    return total_steps // intervals


def resolved(scene, settings: OcpSettings, compiled: bool | None = None):
    """The settings with every number left unset derived from the scene, and how (a phrase).

    Elements, RK4 step and intervals follow :mod:`cable_ocp.control.defaults`; a step the user
    fixed is refused when it is above the model's RK4 limit along the locked run, and one that
    does not divide the duration (or the intervals) is refused too, both naming the setting.

    Returns
    -------
    (OcpSettings, str)

    Raises
    ------
    ValueError
        A fixed setting that cannot work. RuntimeError (the locked run's statics or blow-up)
        passes through: :func:`cable_ocp.optimize` reports it as a failed result.
    """
    compiled = settings.compiled if compiled is None else compiled
    duration = scene.numerics.duration
    notes = []
    elements = settings.elements or defaults.reduced_elements(scene)
    if settings.elements is None:
        notes.append(f"reduced model of {elements} elements")
    if settings.step is not None and settings.intervals is not None:
        steps_per_interval(duration, settings.step, settings.intervals)
    if settings.step is not None:
        _check_memory(scene, settings, elements, settings.step, settings.intervals)
    open_loop, _ = WinchProblem.open_loop_scene(scene)
    limit, at = defaults.run_limit(open_loop, elements, duration, compiled)
    choice = None
    if settings.step is not None:
        defaults.check_step(
            settings.step, limit, "step",
            "leave it unset to derive one, or give a smaller step",
        )  # fmt: skip
        steps_per_interval(duration, settings.step, 1)
        step = settings.step
        intervals = settings.intervals or defaults.intervals_for(
            duration, step, defaults.control_intervals(duration)
        )
    else:
        # Nodes on the scene's step ends too: the Hermite acceleration jumps there, and a jump
        # inside an RK4 step of the verifying model costs its bonds (1e-4 m, not converging
        # with h, on a whole-space case with nodes 5.04 s apart at h = 0.1 s). Where no grid
        # of about 5 s fits the scene's steps, the full model's step is shortened to fit it
        # (full_model_scene).
        intervals = settings.intervals or defaults.control_grid(duration, scene.numerics.step)
        step = defaults.step_within(limit, duration / intervals, defaults.STEP_CAP)
        choice = defaults.StepChoice(step, limit, at)
        notes.append(choice.describe("at"))
    if settings.intervals is None:
        notes.append(f"{intervals} intervals of {duration / intervals:.3g} s")
    _check_memory(scene, settings, elements, step, intervals)
    chosen = replace(
        settings,
        model=ModelSettings(elements, step),
        grid=replace(settings.grid, control=settings.control, intervals=intervals),
    )
    text = "derived settings: " + ", ".join(notes) if notes else ""
    return chosen, text


def _check_memory(scene, settings: OcpSettings, elements: int, step: float, intervals) -> None:
    """Refuse a transcription whose arrays cannot fit in memory, naming the step."""
    intervals = intervals or defaults.control_intervals(scene.numerics.duration)
    size = scene.winch.knots if settings.control == "spline" else 2 * intervals
    estimate = optimisation_memory(scene, step, elements=elements, parameters=size)
    check_memory(
        estimate,
        f"step = {step:g} s of the optimisation model",
        "give a larger step, or leave it unset to derive one",
    )


def shooting_problem(scene, settings: OcpSettings, jacobian: bool = False) -> WinchProblem:
    """The scene's winch problem with the control, model and step of resolved settings.

    ``settings`` come from :func:`resolved` (every number set); with compiled models, the
    libraries that the solve and its verification load start compiling first
    (:func:`compile_ahead`, the model's Jacobian too when the solver needs it: ``jacobian``).
    """
    steps_per_interval(scene.numerics.duration, settings.step, settings.intervals)
    if settings.compiled:
        compile_ahead(scene, settings.elements, jacobian)
    return WinchProblem.from_scene(
        scene, make_control(scene, settings), settings.elements, settings.step, settings.compiled
    )


def compile_ahead(scene, elements: int | None, jacobian: bool) -> None:
    """Start compiling, side by side, the libraries that a solve and its verification load.

    Those not in the disk cache: Gauss-Newton's Jacobian first (``jacobian``; the solve waits for
    it), then the structured libraries of the optimisation model (of ``elements``) and of the
    scene's model (the verification's, a closed loop's plant). Their C compilers run at once
    while the problem and the transcription are built (on paper_hill with an empty cache the
    default ``optimize`` took 7.5 and 8.7 s against 12.9 and 13.1 s compiling one after the other).
    """
    reduced = CableModel.from_scene(scene, elements)
    if jacobian:
        compile_rhs_jacobian_in_background(reduced)
    structured.compile_library_in_background(reduced.parametric)
    structured.compile_library_in_background(CableModel.from_scene(scene).parametric)


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


def _interval_function(step_function, step, steps, seabed) -> ca.Function:
    """``(x, stage inputs, bias, end offset, reference) -> (x_end, int e^2 dt, e)`` on an interval.

    ``e = z_E + b_z - z_ref - z_sb(x_E + b_x, y_E + b_y) + bias`` at the RK4 points (eq. 39
    with the named parameters of :mod:`cable_ocp.control.parameters`); ``e`` after the start.
    """
    size = step_function.size1_in(0)
    x = ca.MX.sym("x", size)
    stages = ca.MX.sym("stages", INPUT_SIZE, 3 * steps)
    bias = ca.MX.sym("bias", 1, steps + 1)
    offset = ca.MX.sym("offset", 3)
    reference = ca.MX.sym("reference")
    states = step_function.mapaccum(steps)(x, stages)
    points = ca.horzcat(x, states)
    errors = clearance_error_function(seabed).map(steps + 1)(points[:3, :], offset, reference)
    errors = errors + bias
    cost = ca.mtimes(errors**2, ca.DM(trapezoid_weights(step, steps + 1)))
    return ca.Function(
        "interval", [x, stages, bias, offset, reference], [states[:, -1], cost, errors[1:]]
    )


class ShootingProblem(ProblemSolver):
    """The shooting NLP of a winch problem for IPOPT, built once and solved as often as needed.

    The NLP's parameters are the problem's named parameters
    (:class:`cable_ocp.control.parameters.ProblemParameters`): the open loop sets them once (with
    the bias ``b = e_full - e_reduced`` of model correction), a closed loop at every sample.
    ``Omega^2 = 1/H int (e + b)^2 dt + w 1/H int (r_D phi')^2 dt`` over the horizon ``H``.

    Parameters
    ----------
    problem : WinchProblem
    settings : OcpSettings
        Resolved (every number set); its solver settings are IPOPT's.
    quiet : bool
        Print nothing.
    verbose : bool
        Print IPOPT's own log and timing table instead of one progress line per iteration.
    rate_weight : float, s^2
        Weight ``w`` of the pay-out speed (0 in the open loop).
    """

    def __init__(
        self,
        problem: WinchProblem,
        settings: OcpSettings,
        quiet: bool = False,
        verbose: bool = False,
        rate_weight: float = 0.0,
    ):
        check_verbosity(quiet, verbose)
        started = time.perf_counter()
        self.problem, self.settings = problem, settings
        ipopt = settings.solver_settings
        duration, step = problem.duration, problem.step
        model, control = problem.model, problem.control
        self.per_interval = per_interval = steps_per_interval(duration, step, settings.intervals)
        total_steps = per_interval * settings.intervals

        values, named = symbols(model.state_size, total_steps)
        winch = ca.MX.sym("winch", control.size)
        inputs = stage_matrix(problem, named, winch)
        bias_rows = ca.horzcat(
            *[
                named["bias"][k * per_interval : (k + 1) * per_interval + 1].T
                for k in range(settings.intervals)
            ]
        )
        step_function, report = ocp_step(model, step, settings.compiled)
        self.compile_time = report.compile_time if report is not None else 0.0
        interval = _interval_function(step_function, step, per_interval, problem.scene.seabed)
        arguments = (inputs, bias_rows, named["end_offset"], named["reference"])
        if settings.transcription.shooting == "single":
            run = interval.mapaccum(settings.intervals)
            _, costs, errors = run(named["initial_state"], *arguments)
            nodes, continuity = ca.MX(model.state_size, 0), ca.MX(0, 1)
        else:
            nodes = ca.MX.sym("nodes", model.state_size, settings.intervals)
            starts = ca.horzcat(named["initial_state"], nodes[:, :-1])
            mapped = interval.map(settings.intervals, "thread", settings.transcription.threads)
            ends, costs, errors = mapped(starts, *arguments)
            continuity = ca.vec(ends - nodes)
            states = step_function.mapaccum(total_steps)(named["initial_state"], inputs)
            self._rollout = ca.Function(
                "rollout", [values, winch], [states[:, per_interval - 1 :: per_interval]]
            )
        radius = problem.scene.winch.drum_radius
        rates = ca.sparsify(ca.DM(radius * control.basis(problem.grid)[1])) @ winch
        effort = ca.dot(ca.DM(trapezoid_weights(step, problem.grid.size)), rates**2)
        objective = (ca.sum2(costs) + rate_weight * effort) / duration

        bounds, seabed = problem.bounds, problem.scene.seabed
        variables = ca.vertcat(ca.vec(nodes), winch) if nodes.numel() else winch
        self.node_count = nodes.numel()
        # The hard minimum clearance (delta + e >= c_min, backed off) at every RK4 point.
        clearance = ca.MX(0, 1)
        self.floor = np.zeros(0)
        if seabed.minimum_clearance is not None:
            clearance = ca.vec(errors)
            floor = seabed.minimum_clearance + CLEARANCE_BACKOFF - seabed.clearance
            self.floor = np.full(clearance.numel(), floor)
        constraints = ca.densify(
            ca.vertcat(continuity, ca.sparsify(ca.DM(bounds.matrix)) @ winch, clearance)
        )
        self.continuity = np.zeros(continuity.numel())
        self.history: list[float] = []
        self.log = IterationLog("ipopt", quiet=quiet or verbose)
        self._callback = _History(
            self.history,
            self.log,
            np.concatenate([self.continuity, bounds.lower, self.floor]),
            np.concatenate([self.continuity, bounds.upper, np.full(self.floor.size, np.inf)]),
        )
        options = {
            "ipopt": ipopt_options(
                ipopt.hessian, ipopt.max_iter, ipopt.tolerance, verbose, ipopt.ipopt_options
            ),
            "print_time": verbose,
            "iteration_callback": self._callback,
            # IPOPT's trial points may blow a reduced model up (NaN); its line search backs
            # off, so CasADi's warning about them is noise (a real failure is in the status).
            "show_eval_warnings": False,
        }
        self.solver = ca.nlpsol(
            "winch_ocp",
            "ipopt",
            {"x": variables, "f": objective, "g": constraints, "p": values},
            options,
        )
        self.build_time = time.perf_counter() - started

    def run(self, values, guess, fixed, lower, upper) -> SolverOutcome:
        """IPOPT from ``guess`` (:meth:`ProblemSolver.solve`).

        With multiple shooting the nodes start from the model's run under ``guess``, or at the
        initial state where that run blows up.
        """
        problem, size = self.problem, self.problem.control.size
        packed = values.pack()
        nodes = np.zeros(0)
        if self.node_count:
            run = np.array(self._rollout(packed, guess))
            if not np.all(np.isfinite(run)):
                run = np.tile(values.initial_state[:, None], (1, run.shape[1]))
            nodes = run.ravel(order="F")
        lbx = np.full(self.node_count + size, -np.inf)
        ubx = np.full(self.node_count + size, np.inf)
        for index, value in fixed.items():
            lbx[self.node_count + index] = ubx[self.node_count + index] = value
            guess[index] = value
        bounds = problem.bounds
        lbg = np.concatenate(
            [self.continuity, bounds.lower if lower is None else lower, self.floor]
        )
        ubg = np.concatenate(
            [
                self.continuity,
                bounds.upper if upper is None else upper,
                np.full(self.floor.size, np.inf),
            ]
        )
        self._callback.lbg, self._callback.ubg = lbg, ubg
        self.history.clear()
        self.log.restart()
        started = time.perf_counter()
        solution = interrupted_solve(
            self.solver,
            x0=np.concatenate([nodes, guess]),
            p=packed,
            lbx=lbx,
            ubx=ubx,
            lbg=lbg,
            ubg=ubg,
        )
        solve_time = time.perf_counter() - started
        stats = self.solver.stats()
        iterations = int(stats["iter_count"])
        return SolverOutcome(
            parameters=np.array(solution["x"][-size:]).ravel(),
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


def stage_matrix(problem: WinchProblem, named: dict, winch: ca.MX) -> ca.MX:
    """The stage inputs (15, 3 K) of the NLP: the named parameters plus the winch profile.

    The winch adds ``r_D (phi, phi', phi'')`` of its control to the top-element rows at the RK4
    stages (:func:`cable_ocp.drive.drive.stage_times`, end stages from the left).
    """
    times, left = stage_times(problem.grid[:-1], problem.step)
    radius = problem.scene.winch.drum_radius
    basis = problem.control.basis(times, left)
    profile = ca.vertcat(*[(radius * ca.sparsify(ca.DM(b)) @ winch).T for b in basis])
    return ca.vertcat(named["top_motion"], named["winch_base"] + profile, named["end_force"])


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
