"""IPOPT on the direct-shooting transcription: its settings, its options and its solver.

The transcription (the intervals, the RK4 step, the clearance error, the stage inputs) is
:mod:`cable_ocp.control.shooting`'s; here it becomes CasADi's NLP for IPOPT, single or multiple
shooting, built once per problem and solved as often as asked (the registry's rules,
:mod:`cable_ocp.control.solvers`).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import casadi as ca
import numpy as np

from cable_ocp.control.checks import Rule, check_fields, check_ipopt_options
from cable_ocp.control.gauss_newton import CLEARANCE_BACKOFF
from cable_ocp.control.interrupts import keeping_interrupts
from cable_ocp.control.parameters import symbols
from cable_ocp.control.problem import ProblemSolver, SolverOutcome, WinchProblem
from cable_ocp.control.settings import OcpSettings
from cable_ocp.control.shooting import (
    interval_function,
    ocp_step,
    stage_matrix,
    steps_per_interval,
)
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


# IPOPT's options in the closed loop (the baseline): warm-started from the shifted plan.
IPOPT_WARM_START = {"warm_start_init_point": "yes", "mu_init": 1e-3}


def warm_started(settings: IpoptSettings) -> IpoptSettings:
    """IPOPT's settings with the closed loop's warm start (the user's options win)."""
    return replace(settings, ipopt_options={**IPOPT_WARM_START, **settings.ipopt_options})


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


class Ipopt(ProblemSolver):
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
        interval = interval_function(step_function, step, per_interval, problem.scene.seabed)
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
