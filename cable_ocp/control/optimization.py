"""The front door for optimal winch control: ``optimize(scene, solver=...)``.

``solver`` is ``"gauss-newton"`` (the default) or ``"ipopt"`` (both on the direct-shooting
transcription), or ``"nelder-mead"`` (the paper's method over spline knots): the registry of
:mod:`cable_ocp.control.solvers`. The model, the control grid and the transcription are
separate settings (:mod:`cable_ocp.control.settings`), the solver's own beside them.

Whatever model the optimiser works on, the result's Omega comes from a simulation of the scene's
own model with the optimised winch angle. With a reduced optimisation model, IPOPT's answer is
refined by model correction: the NLP is solved again with the bias ``b = e_full - e_reduced`` of the
last winch profile added to its clearance error, so the reduced model steers while the full model
keeps score (CONVENTIONS.md §5, "reduced models for optimisation").
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from types import MappingProxyType

import numpy as np
import xarray as xr

from cable_ocp import result_files
from cable_ocp.control.adaptive_grid import Adaptation
from cable_ocp.control.hermite_nodes import HermiteNodes
from cable_ocp.control.keywords import refuse_unknown
from cable_ocp.control.parameters import ProblemParameters
from cable_ocp.control.problem import SolverOutcome, WinchProblem
from cable_ocp.control.settings import (
    GridSettings,
    ModelSettings,
    OcpSettings,
    TranscriptionSettings,
)
from cable_ocp.control.shooting import (
    candidate_settings,
    control_of,
    full_model_scene,
    make_control,
)
from cable_ocp.control.solvers import SHOOTING, SOLVERS, Solver, ocp_settings, transcription_named
from cable_ocp.control.verification import (
    Verification,
    correction_step,
    fitted_step,
    verify_profile,
)
from cable_ocp.drive.drive import Drive
from cable_ocp.drive.winch import (
    RETIMES,
    check_retime,
    played_then_resting,
    replayed_duration,
)
from cable_ocp.result_files import dataset, format_1, netcdf
from cable_ocp.result_files.units import units_of
from cable_ocp.scene.given import scene_given
from cable_ocp.scene.schema import Scene, scene_of
from cable_ocp.simulation.progress import check_verbosity
from cable_ocp.simulation.statics import check_scene_start
from cable_ocp.simulation.trajectory import OMEGA_RTOL, Trajectory, check_kept

# Model correction stops once a solve improves the verified Omega by less than this factor.
SMALL_GAIN = 0.5
# A correction solve that lowers the corrected model's Omega^2 by less than this share from the
# best verified profile, where it started, is not run on the full model: its verified Omega could
# be lower than the best one's by about half that share, and the correction stops with the best
# (whole-space seed 0 case 18, Omega 12 m: the adaptive grid's second correction lowered Omega^2
# by 1.3e-6 of it, and its run took 0.83 s, a third of the optimisation; over the whole-space
# scenes of seeds 0 and 1 the runs left out would have lowered Omega by 4.9e-5 of it at most, and
# every VALIDATION row stayed the same).
UNMOVED = 1e-4


@dataclass(frozen=True, eq=False)
class OcpResult(result_files.KeptInFolder):
    """An optimised winch profile, verified on the scene's full model.

    Attributes
    ----------
    method : str
        The transcription: ``"shooting"`` (direct shooting, by Gauss-Newton or IPOPT) or
        ``"nelder-mead"`` (the paper's knots); files written before the solvers were named say
        ``"ipopt"`` for shooting, read as ``"shooting"``.
    parameters : array
        Winch parameters of the control (rad, rad/s).
    control : str
        ``"spline"`` or ``"hermite"`` with its size, e.g. ``"spline(14)"``.
    trajectory : Trajectory or None
        The scene's full model driven by the optimised winch; None when no profile passed
        verification.
    omega : float, m
        Omega (eq. 39) of ``trajectory`` (NaN without one).
    omega_model : float, m
        Omega on the optimisation model, as the optimiser saw it.
    success : bool
        False when the solver did not converge (or ran out of evaluations), or when its profile
        failed verification: a winch bound broken by more than
        :data:`cable_ocp.drive.bounds.BOUND_TOLERANCE`, or the full-model simulation raised.
    status : str
        The solver's own status message, or ``"verification failed: <reason>"``.
    iterations : int
        Iterations of the solver (of every solve, with model correction).
    evaluations : int
        Objective evaluations (Nelder-Mead) or NLP objective evaluations (IPOPT).
    wall_time : float, s
        Everything, including building and verification.
    build_time : float, s
        Building the NLP (symbolic work and compiling), reported apart.
    solve_time : float, s
        Time inside the solver(s).
    function_time : float, s
        Of ``solve_time``, the part spent evaluating NLP functions and derivatives (IPOPT).
    history : list of float, m
        The objective as an Omega, for every solver in m: the square root of the objective at
        each iteration (Gauss-Newton and IPOPT; Omega on the optimisation model, the rate
        penalty included when ``rate_weight`` > 0), or the best Omega after each evaluation
        (Nelder-Mead).
    refinements : list of float, m
        Omega of the full model after each solve; more than one entry with model
        correction. The reported solve's is its verification at the scene's step, the others'
        come from the correction runs at a coarser step (``notes`` gives it;
        :func:`cable_ocp.control.verification.correction_step`). NaN where a solve's profile
        had no run: the adaptive grid's first solve, which only chooses its nodes, and a solve
        whose run failed.
    compile_time : float, s
        Of ``build_time``, compiling C (0 when the libraries came from the disk cache).
    verification_time : float, s
        Checking the bounds and simulating the scene's model with the optimised winch.
    bound_time : float, s
        How long the verified winch rode a bound (within
        :data:`cable_ocp.control.verification.BOUND_RIDE`): a bound-limited optimum, which is a
        success all the same.
    bond_residual : float, m
        Largest bond residual of the verified run, the health check of its simulation.
    verified_step : float, s
        RK4 step of the verified run: the scene's, or a halving of it when the run at the
        scene's step left its bonds (see ``notes``).
    heave_feedforward : bool
        The scene heaves and the winch pays the heave out (eq. 38) under the optimised profile:
        ``parameters`` are the slow profile on top, ``trajectory.winch_angle`` the sum.
    notes : str
        What the user should know beyond the status (bound riding, a refined verification step).
    minimum_clearance : float, m
        Smallest clearance ``z_E - z_sb`` (= delta + e) of the verified run; a profile under
        ``seabed.minimum_clearance`` (by more than 1 mm) is not a success.
    minimum_clearance_time : float, s
        When the verified run reached it.
    scene_record : dict
        The scene the profile was verified on, as :meth:`~cable_ocp.scene.schema.Scene.to_dict`
        gives it: the user's with its overrides, and with what the verification changed (the
        heave compensation of a feedforward, a step that puts the control's nodes on step ends;
        ``notes`` says which). :attr:`scene` rebuilds it; empty in files written before it.
    solver : str
        The solver that ran: ``"gauss-newton"``, ``"ipopt"`` or ``"nelder-mead"`` (empty in
        files written before it was recorded).
    settings : dict
        The settings it ran with, every number as resolved from the scene
        (:meth:`~cable_ocp.control.settings.OcpSettings.record`: the solver's name, the model,
        grid, transcription and solver settings as tables);
        :func:`cable_ocp.control.solvers.ocp_settings_from_record` rebuilds them, so that
        ``optimize(result.scene, settings=...)`` solves the same problem again. Empty in files
        written before it was kept, and when the settings could not be resolved.
    nodes : list of float, s
        The Hermite control's node times where they are not equally spaced (an adaptive grid's,
        or ``GridSettings.nodes``); empty for equal intervals, the spline, and in files written
        before it was kept.
    """

    FILE, WHAT, FORMAT_1 = "result.nc", "optimisation result", "result.json"  # save/load

    # CF units of the fields kept as variables (result_files.units).
    UNITS = MappingProxyType({
        "omega": "m", "omega_model": "m", "success": "1", "iterations": "1", "evaluations": "1",
        "wall_time": "s", "build_time": "s", "solve_time": "s", "function_time": "s",
        "history": "m", "refinements": "m", "compile_time": "s", "verification_time": "s",
        "bound_time": "s", "bond_residual": "m", "verified_step": "s", "heave_feedforward": "1",
        "minimum_clearance": "m", "minimum_clearance_time": "s", "nodes": "s",
    })  # fmt: skip
    method: str
    parameters: np.ndarray
    control: str
    trajectory: Trajectory | None
    omega: float
    omega_model: float
    success: bool
    status: str
    iterations: int
    evaluations: int
    wall_time: float
    build_time: float
    solve_time: float
    function_time: float
    history: list[float] = field(default_factory=list)
    refinements: list[float] = field(default_factory=list)
    compile_time: float = 0.0
    verification_time: float = 0.0
    bound_time: float = 0.0
    bond_residual: float = float("nan")
    verified_step: float = float("nan")
    heave_feedforward: bool = False
    notes: str = ""
    minimum_clearance: float = float("nan")
    minimum_clearance_time: float = float("nan")
    scene_record: dict = field(default_factory=dict)
    solver: str = ""
    settings: dict = field(default_factory=dict)
    nodes: list[float] = field(default_factory=list)

    @property
    def scene(self):
        """The scene the profile was verified on (a validated ``Scene``; see ``scene_record``)."""
        name = self.trajectory.scene_name if self.trajectory is not None else "scene"
        return scene_of(self.scene_record, name)

    @property
    def duration(self) -> float | None:
        """The horizon T (s) the profile was optimised over; None in files without their scene."""
        return self.scene.numerics.duration if self.scene_record else None

    def winch_profile(self, scene=None, retime: str | None = None):
        """The optimised winch angle as ``t -> (phi, phi', phi'')`` (rad, rad/s, rad/s^2).

        Parameters
        ----------
        scene : Scene, optional
            The scene to drive (default: :attr:`scene`). Where the profile rides on a heave
            feedforward (``heave_feedforward``) and this scene does not compensate its heave,
            the feedforward (eq. 38) is added, so that ``simulate(scene, winch=result)`` drives
            the winch as the verification did on either scene.
        retime : {None, "hold", "stretch"}
            On a scene of another ``numerics.duration`` than :attr:`duration`: None refuses it
            (a profile laid over another horizon is stretched in time), ``"hold"`` plays it in
            its own time and brings the winch to rest after its end, ``"stretch"`` lays it over
            the scene's duration (:data:`~cable_ocp.drive.winch.RETIMES`; :meth:`retimed`).

        Raises
        ------
        ValueError
            Another duration with ``retime`` None, naming both and the choices.
        """
        scene = scene if scene is not None else self.scene
        wanted = "result.retimed({})"
        own = replayed_duration(self.duration, scene.numerics.duration, retime, wanted)
        control = control_of(self.control, own, self.nodes)
        profile = control.angle_function(self.parameters)
        if own < scene.numerics.duration:
            profile = played_then_resting(profile, own)
        if self.heave_feedforward and not scene.top.heave_compensated:
            compensated = scene.updated({"top.heave.compensation": True})
            return Drive.from_scene(compensated, profile).winch_angle
        return profile

    def retimed(self, retime: str) -> RetimedOptimum:
        """The optimum to replay on a scene of another duration as ``retime`` says.

        ``co.simulate(scene, winch=result.retimed("hold"))``: see :meth:`winch_profile`.
        """
        check_retime(retime)
        return RetimedOptimum(self, retime)

    def winch_angle(self, t) -> np.ndarray:
        """The drum's angle (rad) at the times ``t`` (s) on :attr:`scene`.

        As the verified run turned it: the heave's pay-out included where it rode on one.
        """
        scene = self.scene
        drive = Drive.from_scene(scene, self.winch_profile(scene))
        return drive.winch_angle(np.atleast_1d(np.asarray(t, dtype=float)))[0]

    def summary(self) -> dict:
        """The scalar figures of the result (json-ready), named as its fields.

        Named as in ``MpcResult.summary`` where the quantity is the same (``omega``,
        ``success``, ``status``, ``iterations``, ``solve_time``, ``wall_time``,
        ``build_time``); ``"units"`` gives the unit of each figure that has one (from the
        Attributes above: Omega in m, times in s).
        """
        names = (
            "solver", "method", "control", "success", "status", "omega", "omega_model",
            "iterations", "evaluations", "wall_time", "build_time", "solve_time",
            "verification_time", "bound_time", "bond_residual", "verified_step",
            "minimum_clearance", "minimum_clearance_time", "heave_feedforward", "notes",
        )  # fmt: skip
        figures = {name: getattr(self, name) for name in names}
        figures["refinements"] = list(self.refinements)
        return {**figures, "units": units_of(type(self), figures)}

    def to_xarray(self) -> xr.Dataset:
        """The result as an ``xarray.Dataset``, its verified trajectory over ``time`` included.

        ``parameters`` lie over ``parameter``, ``history`` over ``iteration`` (an evaluation for
        Nelder-Mead), ``refinements`` over ``solve``; the numbers are 0-d variables, the strings
        attributes, the trajectory's variables join them (:mod:`cable_ocp.result_files.dataset`,
        a name the result uses too prefixed ``trajectory_``). Every variable carries ``units``
        and ``long_name``.
        """
        units = {"parameters": PARAMETER_UNITS.get(self.control.partition("(")[0], "rad")}
        return dataset.to_dataset(self, type(self).__name__, RESULT_DIMS, units=units)

    @classmethod
    def from_xarray(cls, data: xr.Dataset) -> OcpResult:
        """The result a Dataset of :meth:`to_xarray` holds (an older file's too).

        A history in m^2 (IPOPT and Gauss-Newton in files of format 2) is turned into m.

        Raises
        ------
        ValueError, KeyError, TypeError
            A field is missing or does not fit, or the verified run does not fit its own
            series and scene, or the result's ``scene_record`` is not the run's
            (:func:`~cable_ocp.simulation.trajectory.check_kept`: a forged file).
        """
        from cable_ocp.scene.records import control_parameters

        values = dataset.from_dataset(cls, data)
        values["method"] = transcription_named(values["method"]).name
        control_parameters(values["parameters"], values["control"])
        _check_nodes(values.get("nodes"), values["parameters"])
        if "history" in data.variables and data["history"].attrs.get("units") == "m2":
            values["history"] = omega_history(values["history"])
        run = values["trajectory"]
        if run is not None:
            check_kept(run, netcdf.written_here(data))
            record = values.get("scene_record")
            if record and run.scene_record and record != run.scene_record:
                raise ValueError(
                    "scene_record: not the verified run's (trajectory_scene_record); the "
                    "optimum holds the scene its profile was verified on"
                )
            if not np.isclose(values["omega"], run.omega, rtol=OMEGA_RTOL, atol=0.0):
                raise ValueError(
                    f"omega = {values['omega']:.9g} m: expected the verified run's Omega, "
                    f"{run.omega:.9g} m"
                )
        return cls(**values)

    @classmethod
    def read_format_1(cls, folder: Path) -> OcpResult:
        """The result of cable_ocp 0.1's ``result.json`` and ``result.npz`` in ``folder``."""
        return _from_format_1(cls, folder)


@dataclass(frozen=True)
class RetimedOptimum:
    """An optimum replayed on a scene of another duration, as the user chose (``retime``).

    Anything that takes an ``optimize`` result as its winch takes it (``winch_profile``); a
    closed loop's applied winch is retimed the same way (``MpcResult.retimed``).
    """

    result: OcpResult  # or an MpcResult: its duration and winch_profile(scene, retime)
    retime: str

    def winch_profile(self, scene):
        """The optimum's winch angle on ``scene``, retimed (:meth:`OcpResult.winch_profile`)."""
        return self.result.winch_profile(scene, self.retime)

    def note(self, scene) -> str:
        """What the retiming did on ``scene``, for a run's notes ("" where nothing changed)."""
        own, duration = self.result.duration, scene.numerics.duration
        if own is None or np.isclose(own, duration, rtol=1e-9, atol=1e-9):
            return ""
        return f"the {own:g} s optimum {RETIMES[self.retime]}, on a {duration:g} s scene"


RESULT_FILE, WHAT = OcpResult.FILE, OcpResult.WHAT
RESULT_DIMS = {
    "parameters": ("parameter",), "history": ("iteration",), "refinements": ("solve",),
    "nodes": ("node",),
}  # fmt: skip
# What the docstring cannot state: the parameters' units depend on the control.
PARAMETER_UNITS = {"spline": "rad", "hermite": "rad, then rad s-1 (angles, then rates)"}
# Fields of OcpResult that results written before them lack (their defaults are used).
_OPTIONAL_FIELDS = {
    "compile_time", "verification_time", "bound_time", "bond_residual", "verified_step",
    "heave_feedforward", "notes", "minimum_clearance", "minimum_clearance_time", "scene_record",
    "solver", "settings", "nodes",
}  # fmt: skip


def _check_nodes(nodes, parameters: np.ndarray) -> None:
    """Refuse a result's node times that are not a Hermite grid of its parameters (ValueError)."""
    if nodes is None or np.size(nodes) == 0:
        return
    size = HermiteNodes(np.asarray(nodes, dtype=float)).size  # ValueError naming the nodes
    if size != parameters.size:
        raise ValueError(
            f"nodes: {np.size(nodes)} node times carry {size} parameters, not the "
            f"{parameters.size} of the result"
        )


def node_times(control) -> list[float]:
    """The node times (s) a result keeps: a non-uniform Hermite control's, else none."""
    return control.breakpoints.tolist() if isinstance(control, HermiteNodes) else []


def omega_history(squares: list[float]) -> list[float]:
    """An objective history in m^2 (Omega^2 per iteration) as ``sqrt``, in m."""
    return [float(np.sqrt(max(value, 0.0))) if np.isfinite(value) else value for value in squares]


def _from_format_1(cls, folder: Path) -> OcpResult:
    """An OcpResult from ``result.json``, ``result.npz`` and the trajectory's files (0.1)."""
    import typing

    from cable_ocp.scene.records import control_parameters, control_size, record_fields

    hints = typing.get_type_hints(cls)  # each field of result.json checked against its type
    saved = [f.name for f in fields(cls) if f.name not in ("parameters", "trajectory")]
    types = {name: hints[name] for name in saved}
    path = folder / "result.json"
    meta = format_1.read_json(path, WHAT)
    with format_1.blame(path, WHAT):
        meta = record_fields(meta, types, _OPTIONAL_FIELDS)
        meta["method"] = transcription_named(meta["method"]).name
        control_size(meta["control"])
    path = folder / "result.npz"
    arrays = format_1.read_arrays(path, WHAT)
    with format_1.blame(path, WHAT):
        parameters = np.asarray(arrays["parameters"], dtype=float)
        control_parameters(parameters, meta["control"])
    if meta["method"] == SHOOTING.name:  # Omega^2 per iteration then
        meta["history"] = omega_history(meta.get("history", []))
    trajectory = None
    if (folder / "trajectory.npz").exists() or (folder / "trajectory.json").exists():
        trajectory = Trajectory.load(folder / "trajectory")  # a ValueError naming its file
    return cls(parameters=parameters, trajectory=trajectory, **meta)


def _timed_verify(problem: WinchProblem, quiet: bool, compiled: bool):
    """:func:`verify_profile` on the problem's scene and control that adds up its wall time.

    Returns (verify, elapsed) callables. A profile verified again at the same step (bit for bit
    the same parameters: a model-correction solve that did not move them, on 6 of whole-space
    seed 0's first 20 scenes before such a solve from the best profile was left unrun,
    :data:`UNMOVED`) gets the last verdict back without a second run: the run is
    deterministic, so it would be the same (0.11-1.1 s, a fifth to a third of ``optimize``).
    """
    elapsed = [0.0]
    last: list = [None, None]  # (parameters' bytes, step) and its verdict

    def verify(parameters: np.ndarray, step: float | None = None) -> Verification:
        if step is not None and step <= problem.scene.numerics.step:
            step = None  # the scene's own step, however it was asked for
        key = (np.asarray(parameters, dtype=float).tobytes(), step)
        if last[0] == key:
            return last[1]
        begun = time.perf_counter()
        checked = verify_profile(
            problem.scene, problem.control, parameters, quiet=quiet, compiled=compiled, step=step
        )
        elapsed[0] += time.perf_counter() - begun
        last[:] = key, checked
        return checked

    return verify, lambda: elapsed[0]


def solve_verified(
    problem: WinchProblem,
    settings: OcpSettings,
    refinements: int = 3,
    quiet: bool = False,
    verbose: bool = False,
    verify_compiled: bool | None = None,
    adapt: Adaptation | None = None,
) -> OcpResult:
    """A solver of the registry on a problem, verified and refined on its scene.

    Parameters
    ----------
    problem : WinchProblem
    settings : OcpSettings
        Resolved.
    refinements : int
        Model-correction solves after the first (0 disables them); they stop early when the
        verified Omega stops improving. Ignored when the optimisation model is the scene's own.
    quiet : bool
        Print nothing.
    verbose : bool
        IPOPT's full log instead of one progress line per iteration.
    verify_compiled : bool, optional
        Verify on the compiled full model (default: as the transcription is compiled).
    adapt : Adaptation, optional
        An adaptive grid's coarsening (:class:`cable_ocp.control.adaptive_grid.Adaptation`),
        called on the first solve's optimum before any full-model run; the model correction's
        solves (as many as the default grid's, at least one) then run on the problem it returns,
        their full-model runs at a step that fits its nodes
        (:func:`cable_ocp.control.verification.fitted_step`).

    Returns
    -------
    OcpResult
        ``success`` is False, with the reason in ``status``, when a solve fails (the solver's
        status) or its profile fails verification (``"verification failed: ..."``); the result
        then holds the best verified profile, if any.
    """
    started = time.perf_counter()
    solver = SOLVERS[settings.solver]
    nlp = solver.build(problem, settings, quiet, verbose, 0.0)
    build_time, compile_time = nlp.build_time, nlp.compile_time
    compiled = settings.compiled if verify_compiled is None else verify_compiled
    verify, verification_time = _timed_verify(problem, quiet, compiled)
    coarsening = None
    outcomes: list[SolverOutcome] = []
    verified: list[float] = []
    best_outcome, best, checked, failure = None, None, None, None
    values = problem.parameter_values()
    landing_bias = values.bias  # a landing's reference (-e_ref), zero on other scenes
    parameters = problem.first_guess(compiled=settings.compiled)
    solver_name = solver.label
    default_solves = 1 + (refinements if problem.reduced else 0)
    # The adaptive grid's first solve, on the default grid, only chooses the nodes.
    solves = default_solves + (adapt is not None)
    # Full-model runs that only steer the model correction take a coarser step; the profile
    # reported is verified at the scene's.
    correction = None
    if default_solves > 1:
        correction = correction_step(problem.scene, compiled, problem.control.breakpoints)
    learned = None  # (full-model run, outcome) the next model correction starts from
    best_solve = None
    fallback, abandoned = None, ""  # the default grid's state while the adaptive grid is tried
    # Why the nodes kept are given up: the next pass takes the default grid's first optimum, and
    # its corrections the default grid's solves after it.
    handing_over = ""
    solve = -1
    while (solve := solve + 1) < solves:
        if handing_over:
            # No profile on the nodes kept verified: the default grid goes on from its own first
            # optimum, verified as its first solve, with all its corrections still to come.
            abandoned = f"{coarsening.describe()} abandoned ({handing_over}): default grid kept"
            problem, nlp, verify, correction, values, landing_bias, outcome = fallback
            fallback, coarsening, adapt, learned, handing_over = None, None, None, None, ""
        else:
            if learned is not None:
                run, source = learned
                parameters = source.parameters
                values = _corrected(
                    problem, values, landing_bias, run, parameters, source.states, settings.compiled
                )
            outcome = nlp.solve(values, parameters)
            outcomes.append(outcome)
        if adapt is not None and coarsening is None and outcome.success:
            # The adaptive grid: the default grid's optimum chooses the nodes, before any
            # full-model run; the solves from here on (the model correction's) run on them.
            coarsening = adapt(problem, nlp, values, outcome.parameters)
            fallback = (problem, nlp, verify, correction, values, landing_bias, outcome)
            problem, parameters = coarsening.problem, coarsening.parameters
            if coarsening.values is not values:  # the candidates' own grid
                values = coarsening.values
                landing_bias = problem.landing_bias()
            if correction is not None:
                nodes = problem.control.breakpoints
                correction = fitted_step(correction, problem.scene.numerics.step, nodes)
            nlp = solver.build(problem, settings, quiet, verbose, 0.0)
            if hasattr(nlp, "start_from"):  # the default grid's Jacobian, carried over
                nlp.start_from(values, parameters, coarsening.linearised)
            build_time += nlp.build_time
            compile_time += nlp.compile_time
            verify, timed = _timed_verify(problem, quiet, compiled)
            verification_time = _summed(verification_time, timed)
            verified.append(float("nan"))  # not run on the full model: not the answer
            continue
        if fallback is not None and best is None and not outcome.success:
            # A solve on the nodes kept failed before one of their profiles verified (whole-space
            # seed 1 case 10 blew the reduced model up on them; a run on them that broke the
            # minimum clearance is not learned from).
            handing_over, solves = outcome.status, solve + 1 + default_solves
            continue
        if not outcome.success:
            failure = f"{solver_name} did not converge: {outcome.status}"
            if best is None:  # show where the failed solve got to, still marked as failed
                checked = verify(outcome.parameters)
                best = checked.trajectory
                best_outcome = outcome if best is not None else None
                verified.append(best.omega if best is not None else float("nan"))
            break
        from_best = best_outcome is not None and parameters is best_outcome.parameters
        if from_best and _model_gain(outcome, solver.history_unit) < UNMOVED:
            verified.append(float("nan"))  # not run on the full model: not the answer
            break
        trial = verify(
            outcome.parameters, _run_step(correction, outcome.omega, best, solve, solves)
        )
        if trial.trajectory is None:
            verified.append(float("nan"))
            failure = (
                f"{solver_name} converged ({outcome.status}); verification failed: {trial.reason}"
            )
            if trial.run is not None and solve + 1 < solves:
                # The full model broke the minimum clearance that the reduced one held: correct
                # the model by that run and solve again.
                learned = (trial.run, outcome)
                continue
            if fallback is not None and best is None:
                # The last profile on the nodes kept failed too (whole-space seed 2 case 2's
                # drum passed its bound between the heave's samples, before they were widened).
                handing_over = "no profile on them verified"
                solves = solve + 1 + default_solves
                continue
            break
        failure = None
        verified.append(trial.trajectory.omega)
        if best is not None and trial.trajectory.omega >= best.omega:
            break
        gain = 0.0 if best is None else _gain(trial.trajectory.omega, best.omega)
        best_outcome, best, checked, best_solve = outcome, trial.trajectory, trial, solve
        learned = (best, best_outcome)
        if gain > SMALL_GAIN:
            break
    if checked is not None and checked.step > problem.scene.numerics.step:
        checked = verify(best_outcome.parameters)  # a correction run: now at the scene's step
        best = checked.trajectory
        verified[best_solve] = best.omega if best is not None else float("nan")
        if best is None:
            failure = (
                f"{solver_name} converged ({best_outcome.status}); verification failed: "
                f"{checked.reason}"
            )
    shown = best_outcome or outcomes[-1]
    history = [v for o in outcomes for v in o.history]
    return OcpResult(
        method=solver.transcription.name,
        solver=settings.solver,
        parameters=shown.parameters,
        control=f"{settings.control}({problem.control.size})",
        nodes=node_times(problem.control),
        trajectory=best,
        omega=best.omega if best is not None else float("nan"),
        omega_model=shown.omega,
        success=failure is None,
        status=shown.status if failure is None else failure,
        iterations=sum(o.iterations for o in outcomes),
        evaluations=sum(o.evaluations for o in outcomes),
        wall_time=time.perf_counter() - started,
        build_time=build_time,
        solve_time=sum(o.solve_time for o in outcomes),
        function_time=sum(o.function_time for o in outcomes),
        history=omega_history(history) if solver.history_unit == "m2" else history,
        refinements=verified,
        compile_time=compile_time,
        verification_time=verification_time(),
        **_verification_fields(
            problem, checked, correction, coarsening.describe() if coarsening else abandoned
        ),
    )


def _corrected(
    problem: WinchProblem,
    values: ProblemParameters,
    landing_bias: np.ndarray,
    run,
    parameters: np.ndarray,
    states: np.ndarray | None,
    compiled: bool,
) -> ProblemParameters:
    """The problem's named parameters with the model correction learned from a full-model run.

    The bias is the full model's clearance error on the problem's grid less the optimisation
    model's under the run's profile (``parameters``; ``states`` its run on the grid, None:
    simulated here), on top of a landing's own (``landing_bias``); none where the model is the
    scene's.
    """
    if not problem.reduced:
        return values
    full_error = np.interp(problem.grid, run.time, run.clearance_error)
    if states is None:
        states = problem.simulate(parameters, compiled=compiled)
    return replace(values, bias=landing_bias + full_error - problem.clearance(states))


def _summed(*timers):
    """One timer (a callable returning seconds) that adds up ``timers``."""
    return lambda: sum(timer() for timer in timers)


def _gain(omega: float, before: float) -> float:
    """A solve's gain on the last verified Omega, ``omega / before`` (m / m).

    1 (nothing gained: the correction stops) where that was 0 already, on a scene with nothing
    to hold (``hanging``: the adaptive grid divided by it).
    """
    return omega / before if before > 0 else 1.0


def _model_gain(outcome: SolverOutcome, unit: str) -> float:
    """The share by which a solve lowered its model's Omega^2 from its start (0: not at all).

    ``unit``: its history's (:attr:`Solver.history_unit`), ``"m2"`` or ``"m"``.
    """
    history = np.asarray(outcome.history, dtype=float) ** (1 if unit == "m2" else 2)
    if history.size < 2:  # no step taken
        return 0.0
    if not history[0] > 0:  # nothing to lower: never "unmoved"
        return 1.0
    return float((history[0] - np.min(history)) / history[0])


def _run_step(
    correction: float | None,
    corrected: float,
    best: Trajectory | None,
    solve: int,
    solves: int,
) -> float | None:
    """The step of the full-model run after a solve: the correction step, or the scene's (None).

    The scene's when no solve may follow, or when this one is likely the last: its Omega on the
    corrected model, ``corrected`` (m; it predicts the full model's once the bias has settled:
    1.295e-4 m against 1.302e-4 m on paper_hill's third solve), improves on the best verified
    one by less than :data:`SMALL_GAIN`. That run still corrects the model if the loop goes on.
    """
    if correction is None or solve + 1 >= solves:
        return None
    if best is not None and corrected > SMALL_GAIN * best.omega:
        return None
    return correction


def _verification_fields(
    problem: WinchProblem,
    checked: Verification | None,
    correction: float | None = None,
    adaptive: str = "",
) -> dict:
    """The OcpResult fields that report the verification of the profile shown.

    ``correction``: the step (s) of the model-correction runs, when there were any;
    ``adaptive``: what the adaptive grid did (:meth:`Coarsening.describe`, or why it was
    abandoned), for the notes.
    """
    adapted = [adaptive] if adaptive else []
    fields = {"heave_feedforward": problem.heave_feedforward, "notes": "; ".join(adapted)}
    if checked is None or checked.trajectory is None:
        return fields
    notes = []
    if checked.bound_time > 0:
        notes.append(f"the winch rode its angle bound for {checked.bound_time:.1f} s")
    if problem.heave_feedforward:
        notes.append("the winch pays out the heave (eq. 38) under the optimised profile")
    if checked.note:
        notes.append(checked.note)
    if correction is not None and correction > problem.scene.numerics.step:
        notes.append(f"model correction learned from full-model runs at h = {correction:g} s")
    notes += adapted
    return {
        **fields,
        "bound_time": checked.bound_time,
        "bond_residual": checked.bond_residual,
        "verified_step": checked.step,
        "notes": "; ".join(notes),
        "minimum_clearance": checked.minimum_clearance,
        "minimum_clearance_time": checked.minimum_clearance_time,
    }


# Every keyword optimize() takes (the unknown ones are refused, naming these).
OPTIMIZE_KEYWORDS = (
    "scene", "solver", "settings", "model", "grid", "transcription", "quiet", "verbose",
    "refinements",
)  # fmt: skip


def optimize(
    scene,
    solver: str | None = None,
    settings=None,
    *,
    model: ModelSettings | None = None,
    grid: GridSettings | None = None,
    transcription: TranscriptionSettings | None = None,
    quiet: bool = False,
    verbose: bool = False,
    refinements: int | None = None,
    **unknown,
) -> OcpResult:
    """Optimise the winch angle of a scene.

    States the scene's :class:`~cable_ocp.control.problem.WinchProblem` once (with the model and
    control grid asked for), solves it with the solver, and verifies the result on the scene's
    own model.

    Parameters
    ----------
    scene : Scene, str or path-like
        A scene, a scene file's path or a bundled scene's name
        (:func:`~cable_ocp.scene.given.scene_given`).
    solver : {"gauss-newton", "ipopt", "nelder-mead"}, optional
        Gauss-Newton SQP or IPOPT on the direct-shooting transcription, or the paper's
        Nelder-Mead over spline knots (:data:`cable_ocp.control.solvers.SOLVERS`). None: the
        one whose settings are given, else ``"gauss-newton"``.
    settings : GaussNewtonSettings, IpoptSettings or NelderMeadSettings, optional
        The solver's own settings (default: its class's defaults).
    model : ModelSettings, optional
        The optimisation model; unset fields derived from the scene (3 elements, more on a long
        rope; its RK4 step from its limit along the locked run, at most 0.5 s:
        :mod:`cable_ocp.control.defaults`).
    grid : GridSettings, optional
        The control: a Hermite control of about 5 s intervals by default, or Nelder-Mead's
        spline over the scene's knots.
    transcription : TranscriptionSettings, optional
        Single shooting, compiled, by default. The result's ``notes`` say what was derived.
    quiet : bool
        Print nothing at all.
    verbose : bool
        IPOPT's full log (by default, one progress line per iteration); not with ``quiet``.
    refinements : int, optional
        Model-correction solves after the first (default 3; :func:`solve_verified`), for the
        solvers whose transcription refines by model correction (the shooting ones).
    **unknown
        Refused (TypeError naming the allowed keywords; ``method=`` of an earlier release says
        that it is ``solver=`` now).

    Returns
    -------
    OcpResult
        Check ``success``: a failed solve is returned with ``success = False`` and the solver's
        status, never as an answer; ``solver`` names the solver that ran. On a valid scene it
        never raises: a failure of the physics on the way (no equilibrium, a simulation that
        blows up, a solver error) is such a result, with the reason and a remedy.

    Raises
    ------
    ValueError
        Bad input (a solver, setting or scene field out of range, settings that do not fit
        together), before any heavy work.
    TypeError
        A ``scene`` that is neither a scene nor a scene file's path or name.
    OffGridError
        The scene's end starts off its bathymetry grid or under its seabed (its statics, before
        any solve; :func:`~cable_ocp.simulation.statics.check_scene_start`).
    """
    refuse_unknown("optimize", unknown, OPTIMIZE_KEYWORDS)
    check_verbosity(quiet, verbose)
    scene = scene_given(scene, "optimize")
    refuse_line_scene(scene, "optimize")
    check_scene_start(scene)
    settings = ocp_settings(solver, settings, model, grid, transcription)
    requested = settings
    entry = SOLVERS[settings.solver]
    chosen = entry.transcription
    options = _solve_options(entry, refinements)
    started = time.perf_counter()
    model_text = "the optimisation model"
    try:
        settings, scene, derived = resolved_scene(chosen, scene, settings)
        model_text = (
            f"the optimisation model ({settings.elements} elements at h = {settings.step:.4g} s"
            f"{'; ' + derived if derived else ''})"
        )
        problem = chosen.problem(scene, settings, entry.needs_compiled)
        adapt = None
        if settings.grid.adaptive:
            adapt = _adaptation(problem, chosen, requested, settings, entry.needs_compiled)
        result = solve_verified(
            problem, settings, quiet=quiet, verbose=verbose, adapt=adapt, **options
        )
    except RuntimeError as error:  # SimulationError, EquilibriumError, CasADi's errors
        elapsed = time.perf_counter() - started
        return failed_result(chosen.name, settings, error, elapsed, model_text)
    if result.nodes:  # the adaptive grid's nodes: given, they solve on the same grid
        grid = replace(settings.grid, adaptive=False, nodes=tuple(result.nodes))
        settings = replace(settings, grid=grid)
        if adapt is not None and adapt.finer is not None:  # among finer candidates, on their step
            settings = replace(settings, model=replace(settings.model, step=adapt.finer.step))
    notes = "; ".join(text for text in (result.notes, derived) if text)
    ran = result.trajectory.scene_record if result.trajectory is not None else scene.to_dict()
    return replace(result, notes=notes, scene_record=ran, settings=settings.record())


def resolved_scene(
    transcription, scene: Scene, settings: OcpSettings
) -> tuple[OcpSettings, Scene, str]:
    """What ``optimize`` derives before it builds its problem: the settings and the scene.

    Returns the settings resolved on ``scene`` by ``transcription`` (model, step, grid), the
    scene whose full model verifies (its step fitted to the control's nodes where needed,
    :func:`~cable_ocp.control.shooting.full_model_scene`) and the notes on what was derived.
    """
    settings, derived = transcription.resolve(scene, settings)
    scene, fitted = full_model_scene(scene, settings)
    return settings, scene, "; ".join(text for text in (derived, fitted) if text)


def _adaptation(problem: WinchProblem, chosen, requested, settings, compiled: bool) -> Adaptation:
    """The adaptive grid's coarsening, with the problem on its candidates built only if taken.

    ``problem`` is the first solve's, on the default grid of ``settings``; ``requested`` are the
    settings before :meth:`resolve` made them. The candidates split each default interval in
    ``adaptive_finest`` (:func:`cable_ocp.control.shooting.candidate_settings`); on the same
    model step, their problem is ``problem`` with their control.
    """
    if settings.grid.adaptive_finest == 1:
        return Adaptation(settings.grid.adaptive_tolerance)
    scene = problem.scene

    def candidates() -> WinchProblem:
        split = candidate_settings(scene, requested, settings)
        if split.step == problem.step:
            return problem.with_control(make_control(scene, split))
        return chosen.problem(scene, split, compiled)

    return Adaptation(settings.grid.adaptive_tolerance, candidates)


def _solve_options(entry: Solver, refinements: int | None) -> dict:
    """:func:`solve_verified`'s options for a solver's transcription (ValueError on a misfit)."""
    transcription = entry.transcription
    if transcription.model_correction:
        return {"refinements": 3 if refinements is None else refinements}
    if refinements is not None:
        raise ValueError(
            f"refinements = {refinements!r}: {entry.label} refines by no model correction; "
            "leave refinements out"
        )
    return {"refinements": 0, "verify_compiled": transcription.verify_compiled}


def refuse_line_scene(scene, what: str) -> None:
    """Refuse a scene whose line is paid out by elements (``[winch.line]``), by name.

    Its element count changes as the drum turns; the winch problem's transcriptions and the
    closed loop keep one model of fixed n.
    """
    if scene.winch.line is not None:
        raise ValueError(
            f"winch.line: {what} works on a fixed number of elements; a line paid out by "
            "elements ([winch.line]) is simulated only (co.simulate): leave [winch.line] out, "
            "and the winch's reach stays in its top element"
            + (
                "; a [lowering] scene lands by co.plan_landing, or from a hover by co.land "
                "(co.landing_scene makes its fixed-n landing)"
                if scene.lowering is not None
                else ""
            )
        )


def failed_result(
    method: str,
    settings: OcpSettings,
    error: Exception,
    wall_time: float,
    model: str = "the optimisation model",
) -> OcpResult:
    """The result of an optimisation that stopped on ``error`` before it had a profile.

    ``model`` names the model that was being worked on (the reduced one, with its settings).
    """
    reason = f"{type(error).__name__} on {model}: {error}"
    return OcpResult(
        method=method,
        parameters=np.zeros(0),
        control=f"{settings.control}(0)",  # no profile: no parameters
        trajectory=None,
        omega=float("nan"),
        omega_model=float("nan"),
        success=False,
        status=f"failed before a profile was found: {reason}",
        iterations=0,
        evaluations=0,
        wall_time=wall_time,
        build_time=0.0,
        solve_time=0.0,
        function_time=0.0,
        solver=settings.solver,
    )
