"""The solvers of the winch problem: one contract, one registry.

Every solver of a :class:`~cable_ocp.control.problem.WinchProblem` keeps these rules (as
SciPy's ``OdeSolver`` states its own), so that ``optimize``, ``mpc``, the sweep and the command
line run any of them alike by its name in :data:`SOLVERS`:

1. It is built once per problem, ``build(problem, settings, quiet, verbose, rate_weight)``, from
   resolved :class:`~cable_ocp.control.settings.OcpSettings` (every number set). The building
   (transcription, symbolic work, compiling C) is timed apart: ``build_time`` and, of it,
   ``compile_time`` (s; 0 on a disk-cache hit).
2. It solves as often as asked: ``solve(values, guess, fixed=None, lower=None, upper=None)``,
   ``values`` the problem's named parameters
   (:class:`~cable_ocp.control.parameters.ProblemParameters`), ``guess`` the winch parameters
   (rad, rad/s) it starts from. ``fixed`` pins parameters (index to value) and ``lower``,
   ``upper`` replace the bound rows' limits: a closed loop's needs. A solver that cannot take
   them (``closed_loop=False``) refuses them with a ValueError.
3. It returns a :class:`~cable_ocp.control.problem.SolverOutcome`, and never raises for a
   solve that fails: ``success`` is False and ``status`` says why, in the solver's words.
   A user's interrupt (Ctrl-C) is re-raised as KeyboardInterrupt, never a failure.
4. The outcome's ``omega`` (m) is Omega on the problem's model, ``history`` its objective per
   iteration (``SolverOutcome``), and its ``parameters`` keep the winch bounds to within
   :data:`cable_ocp.drive.bounds.BOUND_TOLERANCE` when it succeeds.
5. It prints nothing when ``quiet``; otherwise one line per iteration (or a progress bar), and
   with ``verbose`` its own log where it has one.
6. Its own settings are a frozen dataclass, checked field by field when made
   (:mod:`cable_ocp.control.checks`); :func:`ocp_settings` checks what they must agree on with
   the grid and the transcription, before any work.

What differs between solvers is asked of their entry (:class:`Solver`), never decided by
comparing their names: the transcription ``optimize`` states for it, its default control, whether
it needs the compiled model, how the closed loop shoots with it and starts it, and which status
says that its QP had no feasible point. A new solver is one more entry here.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

from cable_ocp.control.gauss_newton import DAQP_INFEASIBLE, GaussNewton, GaussNewtonSettings
from cable_ocp.control.ipopt import Ipopt, IpoptSettings, check_ipopt, warm_started
from cable_ocp.control.nelder_mead import (
    NelderMead,
    NelderMeadSettings,
    nelder_mead_problem,
    resolved_nelder_mead,
)
from cable_ocp.control.settings import (
    GridSettings,
    ModelSettings,
    OcpSettings,
    TranscriptionSettings,
)
from cable_ocp.control.shooting import resolved, winch_problem
from cable_ocp.simulation.progress import IterationLog


@dataclass(frozen=True)
class Transcription:
    """How ``optimize`` states the winch problem for a solver, and verifies its answer.

    Attributes
    ----------
    name : str
        As results record it (``OcpResult.method``): ``"shooting"`` or ``"nelder-mead"``.
    resolve : callable
        ``(scene, settings) -> (settings, str)``: every number left unset derived from the scene
        (:mod:`cable_ocp.control.defaults`), and how (a phrase).
    problem : callable
        ``(scene, settings) -> WinchProblem``: the control, model and step the resolved settings
        ask for.
    model_correction : bool
        A reduced model's answer is refined by model correction (``optimize(refinements=...)``).
    verify_compiled : bool or None
        The full model that verifies: None as the transcription is compiled, False the
        interpreted one (the paper's method as it was measured, VALIDATION.md).
    """

    name: str
    resolve: Callable
    problem: Callable
    model_correction: bool
    verify_compiled: bool | None


SHOOTING = Transcription("shooting", resolved, winch_problem, True, None)
KNOTS = Transcription("nelder-mead", resolved_nelder_mead, nelder_mead_problem, False, False)
# Files and sweeps of before the solvers were named called shooting "ipopt", whichever ran.
OLD_TRANSCRIPTIONS = {"ipopt": SHOOTING.name}
# Grid fields of the adaptive grid's first rule (refinement from every 4th default node), which
# its coarsening rule does without: the settings a file kept with them rebuild without them.
RETIRED_GRID_FIELDS = ("adaptive_start", "adaptive_rounds")


def _as_they_are(settings):
    """A solver's settings, unchanged (a :attr:`Solver.warm_started` with nothing to add)."""
    return settings


@dataclass(frozen=True)
class Solver:
    """One entry of the registry: a solver and what it can do.

    Attributes
    ----------
    name : str
        As ``optimize(solver=...)`` takes it.
    label : str
        As messages print it.
    settings : type
        Its settings class; an instance of it is the default.
    build : callable
        ``(problem, settings, quiet, verbose, rate_weight) -> solver`` (rule 1).
    transcription : Transcription
        How ``optimize`` states the problem for it and verifies its answer.
    default_control : str
        The winch parametrisation when ``GridSettings.control`` is unset: ``"hermite"`` or
        ``"spline"`` (the scene's knots).
    shootings : tuple of str
        The ``TranscriptionSettings.shooting`` it takes (empty: the paper's knots, no shooting).
    needs_compiled : bool
        It works on the compiled transcription only, with its model's Jacobian compiled too
        (``TranscriptionSettings.compiled = False`` is refused; the Jacobian compiles ahead).
    closed_loop_shooting : str or None
        How the closed loop shoots with it (``"single"`` or ``"multiple"``); None: ``mpc`` may
        not run it (it takes no ``fixed``, ``lower`` and ``upper``, rule 2).
    closed_loop_settings : object or None
        Its settings in the closed loop when none are given.
    warm_started : callable
        ``(settings) -> settings``: its settings as the closed loop runs them, started from the
        plan in force (IPOPT's warm start; the others take the settings as they are).
    infeasible : str or None
        The text in a failed solve's ``status`` that says its QP had no feasible point (the
        closed loop then solves again on the winch's own range); None: it reports none.
    history_unit : str
        The unit of its outcome's ``history``: ``"m2"`` (Omega^2, its objective) or ``"m"``
        (Omega); results report Omega, m.
    check : callable or None
        ``(OcpSettings) -> None``: what its own settings must agree on with the transcription,
        a ValueError naming the misfit, before any work.
    """

    name: str
    label: str
    settings: type
    build: Callable
    transcription: Transcription
    default_control: str
    shootings: tuple[str, ...]
    needs_compiled: bool
    closed_loop_shooting: str | None
    closed_loop_settings: object | None
    infeasible: str | None
    history_unit: str
    check: Callable[[OcpSettings], None] | None = None
    warm_started: Callable = _as_they_are

    @property
    def closed_loop(self) -> bool:
        """Whether ``mpc`` may run it."""
        return self.closed_loop_shooting is not None


def _gauss_newton(problem, settings: OcpSettings, quiet, verbose, rate_weight) -> GaussNewton:
    log = None if quiet else IterationLog("gauss-newton")
    return GaussNewton(problem, settings.solver_settings, log, rate_weight)


def _ipopt(problem, settings: OcpSettings, quiet, verbose, rate_weight) -> Ipopt:
    return Ipopt(problem, settings, quiet=quiet, verbose=verbose, rate_weight=rate_weight)


def _nelder_mead(problem, settings: OcpSettings, quiet, verbose, rate_weight) -> NelderMead:
    return NelderMead(problem, settings.solver_settings, settings.compiled, quiet)


SOLVERS: dict[str, Solver] = {
    entry.name: entry
    for entry in (
        Solver(
            "gauss-newton",
            "Gauss-Newton",
            GaussNewtonSettings,
            _gauss_newton,
            SHOOTING,
            default_control="hermite",
            shootings=("single",),
            needs_compiled=True,
            closed_loop_shooting="single",
            # One Gauss-Newton step per sample from the shifted plan, its sensitivities from the
            # Jacobian at the step ends (the real-time iteration).
            closed_loop_settings=GaussNewtonSettings(
                max_iter=1, real_time=True, stage_jacobians="ends"
            ),
            infeasible=DAQP_INFEASIBLE,
            history_unit="m2",
        ),
        Solver(
            "ipopt",
            "IPOPT",
            IpoptSettings,
            _ipopt,
            SHOOTING,
            default_control="hermite",
            shootings=("single", "multiple"),
            needs_compiled=False,
            closed_loop_shooting="multiple",
            # To convergence (its 300 iterations) at a tolerance of 1e-6.
            closed_loop_settings=IpoptSettings(tolerance=1e-6),
            infeasible=None,
            history_unit="m2",
            check=check_ipopt,
            warm_started=warm_started,
        ),
        Solver(
            "nelder-mead",
            "Nelder-Mead",
            NelderMeadSettings,
            _nelder_mead,
            KNOTS,
            default_control="spline",
            shootings=(),
            needs_compiled=False,
            closed_loop_shooting=None,
            closed_loop_settings=None,
            infeasible=None,
            history_unit="m",
        ),
    )
}
DEFAULT_SOLVER = "gauss-newton"


def transcription_named(name: str) -> Transcription:
    """The transcription a result or sweep names, old names too (ValueError naming the choices)."""
    known = {entry.transcription.name: entry.transcription for entry in SOLVERS.values()}
    name = OLD_TRANSCRIPTIONS.get(name, name)
    if name not in known:
        raise ValueError(f"method = {name!r:.40}: must be one of {', '.join(map(repr, known))}")
    return known[name]


def solver_for(method: str | None, solver: str | None) -> str | None:
    """The solver to run when a transcription is named too (a sweep's or the CLI's ``method``).

    ``method`` None: ``solver`` as given. Otherwise a given solver must run on that
    transcription (ValueError naming the ones that do); none given: :data:`DEFAULT_SOLVER` when
    it runs on it, else the first solver that does.
    """
    if method is None:
        return solver
    transcription = transcription_named(method)
    runs = [name for name, entry in SOLVERS.items() if entry.transcription is transcription]
    if solver is None:
        return DEFAULT_SOLVER if DEFAULT_SOLVER in runs else runs[0]
    if solver not in runs:
        raise ValueError(
            f"solver = {solver!r} with method = {method!r}: that method is run by "
            f"{' or '.join(map(repr, runs))}; give one of them, or leave method out"
        )
    return solver


def solver_named(name: str, closed_loop: bool = False) -> Solver:
    """The registry's entry (ValueError naming the choices for an unknown name)."""
    names = [n for n, entry in SOLVERS.items() if entry.closed_loop or not closed_loop]
    if name not in names:
        raise ValueError(f"solver = {name!r}: must be one of {', '.join(map(repr, names))}")
    return SOLVERS[name]


def solver_of(solver: str | None, settings, closed_loop: bool = False) -> tuple[Solver, object]:
    """The solver to run and its settings, from a name, settings, both or neither.

    Neither: :data:`DEFAULT_SOLVER` with its defaults; settings alone: the solver they belong
    to. A name and settings of another solver are refused (ValueError).
    """
    if settings is None:
        entry = solver_named(solver or DEFAULT_SOLVER, closed_loop)
        return entry, entry.settings()
    owners = [entry for entry in SOLVERS.values() if isinstance(settings, entry.settings)]
    if not owners:
        raise ValueError(
            f"settings: {type(settings).__name__} is no solver's settings (one of "
            f"{', '.join(entry.settings.__name__ for entry in SOLVERS.values())})"
        )
    entry = solver_named(solver or owners[0].name, closed_loop)
    if not isinstance(settings, entry.settings):
        raise ValueError(
            f"settings: {type(settings).__name__} given for solver {entry.name!r}, which takes "
            f"{entry.settings.__name__}"
        )
    return entry, settings


def ocp_settings(
    solver: str | None = None,
    settings=None,
    model: ModelSettings | None = None,
    grid: GridSettings | None = None,
    transcription: TranscriptionSettings | None = None,
) -> OcpSettings:
    """The settings of one ``optimize``, their agreement checked (ValueError naming a misfit).

    ``settings`` may be a whole :class:`OcpSettings` (nothing else given then).
    """
    if isinstance(settings, OcpSettings):
        if any(part is not None for part in (solver, model, grid, transcription)):
            raise ValueError(
                "settings: an OcpSettings holds the solver, model, grid and transcription; give "
                "them in it, not beside it"
            )
        solver, model, grid = settings.solver, settings.model, settings.grid
        settings, transcription = settings.solver_settings, settings.transcription
    entry, settings = solver_of(solver, settings)
    for name, part, cls in (("model", model, ModelSettings), ("grid", grid, GridSettings),
                            ("transcription", transcription, TranscriptionSettings)):  # fmt: skip
        if part is not None and not isinstance(part, cls):
            raise ValueError(f"{name} = {part!r:.60}: must be a {cls.__name__}")
    grid, transcription = grid or GridSettings(), transcription or TranscriptionSettings()
    if transcription.shooting not in (entry.shootings or ("single",)):
        takes = (
            " or ".join(map(repr, entry.shootings)) + " shooting"
            if entry.shootings
            else ("no shooting (the knots' spline, one run per evaluation)")
        )
        shooting = transcription.shooting
        others = [name for name, other in SOLVERS.items() if shooting in other.shootings]
        raise ValueError(
            f"TranscriptionSettings.shooting = {transcription.shooting!r}: {entry.label} takes "
            f"{takes}; solver={' or '.join(map(repr, others))} takes {transcription.shooting!r}"
        )
    if entry.needs_compiled and not transcription.compiled:
        raise ValueError(
            f"TranscriptionSettings.compiled = False: {entry.label} works on the compiled "
            "single-shooting transcription; set compiled=True, or solver='ipopt'"
        )
    if grid.control is None:
        grid = replace(grid, control=entry.default_control)
    chosen = OcpSettings(entry.name, settings, model or ModelSettings(), grid, transcription)
    if entry.check is not None:
        entry.check(chosen)
    return chosen


def ocp_settings_from(options: dict, solver: str | None = None) -> OcpSettings:
    """One ``optimize``'s settings from a flat table of field names (a sweep's ``[optimizer]``).

    Each name goes to the object that declares it (:class:`ModelSettings`, :class:`GridSettings`,
    :class:`TranscriptionSettings`, the solver's settings); ``solver`` may be in the table too.
    Unset fields keep their defaults (derived from the scene). ValueError names an unknown key
    with the allowed ones, or a value a field refuses.
    """
    options = dict(options)
    entry = solver_named(options.pop("solver", solver) or DEFAULT_SOLVER)
    classes = [ModelSettings, TranscriptionSettings, entry.settings]
    classes += [GridSettings] if entry.shootings else []
    parts: dict[type, dict] = {cls: {} for cls in classes}
    for name, value in options.items():
        owner = next((cls for cls in classes if name in cls.__dataclass_fields__), None)
        if owner is None:
            allowed = ["solver"] + [name for cls in classes for name in cls.__dataclass_fields__]
            raise ValueError(
                f"{name}: unknown setting for solver {entry.name!r}; allowed: {', '.join(allowed)}"
            )
        parts[owner][name] = value
    made = {cls: cls(**values) for cls, values in parts.items()}
    return ocp_settings(
        entry.name,
        made[entry.settings],
        made[ModelSettings],
        made.get(GridSettings),
        made[TranscriptionSettings],
    )


def ocp_settings_from_record(record: dict) -> OcpSettings:
    """The settings a result kept (:meth:`OcpSettings.record`), rebuilt and checked again."""
    try:
        entry = solver_named(record["solver"])
        return ocp_settings(
            entry.name,
            entry.settings(**record["solver_settings"]),
            ModelSettings(**record["model"]),
            GridSettings(
                **{k: v for k, v in record["grid"].items() if k not in RETIRED_GRID_FIELDS}
            ),
            TranscriptionSettings(**record["transcription"]),
        )
    except (KeyError, TypeError) as error:
        raise ValueError(
            f"settings {record!r:.80}: not a record of OcpSettings ({error!r})"
        ) from None
