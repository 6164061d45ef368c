"""The front door for optimal winch control: ``optimize(scene, method="ipopt" | "nelder-mead")``.

Whatever model the optimiser works on, the result's Omega comes from a simulation of the scene's
own model with the optimised winch angle. With a reduced optimisation model, IPOPT's answer is
refined by model correction: the NLP is solved again with the bias ``b = e_full - e_reduced`` of the
last winch profile added to its clearance error, so the reduced model steers while the full model
keeps score (CONVENTIONS.md §5, "reduced models for optimisation").
"""

from __future__ import annotations

import json
import time
import zipfile
from dataclasses import asdict, dataclass, field, fields
from pathlib import Path

import numpy as np

from cable_ocp.bounds import violation
from cable_ocp.nelder_mead import NelderMeadSettings, solve_nelder_mead
from cable_ocp.ocp import IpoptOutcome, IpoptSettings, ShootingProblem
from cable_ocp.progress import check_verbosity
from cable_ocp.simulation import simulate
from cable_ocp.trajectory import Trajectory

# Model correction stops once a solve improves the verified Omega by less than this factor.
SMALL_GAIN = 0.5


@dataclass(frozen=True, eq=False)
class OcpResult:
    """An optimised winch profile, verified on the scene's full model.

    Attributes
    ----------
    method : str
        ``"ipopt"`` or ``"nelder-mead"``.
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
        :data:`cable_ocp.bounds.BOUND_TOLERANCE`, or the full-model simulation raised.
    status : str
        The solver's own status message, or ``"verification failed: <reason>"``.
    iterations : int
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
    history : list of float
        Objective per iteration (IPOPT: Omega^2 on the optimisation model, m^2) or best Omega per
        evaluation (Nelder-Mead, m).
    refinements : list of float
        Verified Omega after each solve (m); more than one entry with model correction.
    compile_time : float, s
        Of ``build_time``, compiling C (0 when the libraries came from the disk cache).
    verification_time : float, s
        Checking the bounds and simulating the scene's model with the optimised winch.
    """

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

    def save(self, folder: str | Path) -> None:
        """Write ``result.json``, ``result.npz`` and the trajectory into ``folder``.

        NaN (Omega of a profile that could not be verified) is written as JSON ``null``.
        """
        folder = Path(folder)
        folder.mkdir(parents=True, exist_ok=True)
        if self.trajectory is not None:
            self.trajectory.save(folder / "trajectory")
        meta = {
            k: _json_value(v)
            for k, v in asdict(self).items()
            if k not in ("parameters", "trajectory")
        }
        (folder / "result.json").write_text(json.dumps(meta, indent=1, allow_nan=False))
        np.savez(folder / "result.npz", parameters=self.parameters)

    @classmethod
    def load(cls, folder: str | Path) -> OcpResult:
        """Read a result written by :meth:`save`.

        Raises
        ------
        ValueError
            Naming the file, if a file of the result is missing, truncated or garbled.
        """
        folder = Path(folder)
        path = folder / "result.json"
        try:
            meta = json.loads(path.read_text())
            names = {f.name for f in fields(cls)} - {"parameters", "trajectory"}
            if not isinstance(meta, dict) or not names - _OPTIONAL_FIELDS <= set(meta) <= names:
                raise ValueError(f"fields {sorted(meta) if isinstance(meta, dict) else meta!r}")
            meta = {k: _from_json(k, v) for k, v in meta.items()}
            path = folder / "result.npz"
            with np.load(path) as data:
                parameters = np.asarray(data["parameters"], dtype=float)
            path, trajectory = folder / "trajectory.npz", None
            if path.exists():
                try:
                    trajectory = Trajectory.load(folder / "trajectory")
                except json.JSONDecodeError:
                    path = folder / "trajectory.json"
                    raise
        except (OSError, ValueError, KeyError, TypeError, zipfile.BadZipFile, EOFError) as error:
            raise ValueError(
                f"{path}: not a readable optimisation result ({type(error).__name__}: {error})"
            ) from error
        return cls(parameters=parameters, trajectory=trajectory, **meta)


# Fields of OcpResult that results written before them lack (their defaults are used).
_OPTIONAL_FIELDS = {"compile_time", "verification_time"}
# Fields of OcpResult that hold floats which may be NaN.
_FLOAT_FIELDS = ("omega", "omega_model", "history", "refinements")


def _json_value(value):
    """A value for JSON: NaN and infinities as None, inside lists too."""
    if isinstance(value, list):
        return [_json_value(v) for v in value]
    if isinstance(value, float) and not np.isfinite(value):
        return None
    return value


def _from_json(name: str, value):
    """Undo :func:`_json_value` for the field ``name`` (None back to NaN)."""
    if name not in _FLOAT_FIELDS:
        return value
    if isinstance(value, list):
        return [float("nan") if v is None else float(v) for v in value]
    return float("nan") if value is None else float(value)


def _verify(
    scene, control, parameters, quiet, compiled: bool = False
) -> tuple[Trajectory | None, str | None]:
    """Check the winch bounds and simulate the scene's model with the winch.

    ``compiled`` simulates with the model compiled to C (cached on disk).

    Returns
    -------
    (trajectory, None), or (None, reason) when the profile breaks a winch bound beyond
    :data:`cable_ocp.bounds.BOUND_TOLERANCE` or the simulation raises (any exception).
    """
    reason = violation(scene, control, parameters)
    if reason is not None:
        return None, reason
    try:
        winch = control.angle_function(parameters)
        return simulate(scene, winch=winch, quiet=quiet, compiled=compiled), None
    except Exception as error:  # noqa: BLE001 - any failure of the check is a failed result
        return None, f"the full-model simulation raised {type(error).__name__}: {error}"


def optimize_ipopt(
    scene,
    settings: IpoptSettings | None = None,
    refinements: int = 3,
    quiet: bool = False,
    verbose: bool = False,
) -> OcpResult:
    """Direct (single or multiple) shooting + IPOPT, verified (and refined) on the scene's model.

    Parameters
    ----------
    scene : Scene
    settings : IpoptSettings, optional
        Defaults: a reduced model of 3 elements at h = 0.5 s, single shooting, Hermite control
        on 42 intervals; Omega verified on the scene's model compiled to C.
    refinements : int
        Model-correction solves after the first (0 disables them); they stop early when the
        verified Omega stops improving. Ignored when the optimisation model is the scene's own.
    quiet : bool
        Print nothing.
    verbose : bool
        IPOPT's full log instead of one progress line per iteration.

    Returns
    -------
    OcpResult
        ``success`` is False, with the reason in ``status``, when a solve fails (IPOPT's status)
        or its profile fails verification (``"verification failed: ..."``); the result then holds
        the best verified profile, if any.
    """
    started = time.perf_counter()
    settings = settings or IpoptSettings(elements=3, step=0.5)
    problem = ShootingProblem(scene, settings, quiet=quiet, verbose=verbose)
    reduced = (
        problem.model.spec.elements != scene.model.elements or problem.step != scene.numerics.step
    )
    outcomes: list[IpoptOutcome] = []
    verified: list[float] = []
    best_outcome, best, failure = None, None, None
    parameters, bias = problem.first_guess(), None
    verification_time = 0.0

    def verify(parameters):
        nonlocal verification_time
        begun = time.perf_counter()
        checked = _verify(scene, problem.control, parameters, quiet, settings.compiled)
        verification_time += time.perf_counter() - begun
        return checked

    for _ in range(1 + (refinements if reduced else 0)):
        if best is not None:
            full_error = np.interp(problem.grid, best.time, best.clearance_error)
            model_error = problem.clearance(problem.simulate(best_outcome.parameters))
            parameters, bias = best_outcome.parameters, full_error - model_error
        outcome = problem.solve(parameters, bias)
        outcomes.append(outcome)
        if not outcome.success:
            failure = outcome.status
            if best is None:  # show where the failed solve got to, still marked as failed
                best, _ = verify(outcome.parameters)
                best_outcome = outcome if best is not None else None
                verified.append(best.omega if best is not None else float("nan"))
            break
        trial, reason = verify(outcome.parameters)
        if trial is None:
            verified.append(float("nan"))
            failure = f"verification failed: {reason}"
            break
        verified.append(trial.omega)
        if best is not None and trial.omega >= best.omega:
            break
        gain = trial.omega / best.omega if best is not None else 0.0
        best_outcome, best = outcome, trial
        if gain > SMALL_GAIN:
            break
    shown = best_outcome or outcomes[-1]
    return OcpResult(
        method="ipopt",
        parameters=shown.parameters,
        control=f"{settings.control}({problem.control.size})",
        trajectory=best,
        omega=best.omega if best is not None else float("nan"),
        omega_model=float(np.sqrt(max(shown.objective, 0.0))),
        success=failure is None,
        status=shown.status if failure is None else failure,
        iterations=sum(o.iterations for o in outcomes),
        evaluations=sum(o.iterations for o in outcomes) + len(outcomes),
        wall_time=time.perf_counter() - started,
        build_time=problem.build_time,
        solve_time=sum(o.solve_time for o in outcomes),
        function_time=sum(o.function_time for o in outcomes),
        history=[v for o in outcomes for v in o.history],
        refinements=verified,
        compile_time=problem.compile_time,
        verification_time=verification_time,
    )


def _nelder_mead_status(outcome, reason: str | None) -> str:
    """The search's message, with the verification's failure where there is one."""
    if reason is None:
        return outcome.message
    failed = f"verification failed: {reason}"
    return failed if outcome.success else f"{outcome.message}; {failed}"


def optimize_nelder_mead(
    scene,
    settings: NelderMeadSettings | None = None,
    quiet: bool = False,
    verbose: bool = False,
) -> OcpResult:
    """The paper's Nelder-Mead over the spline knots, verified on the scene's model.

    Parameters
    ----------
    scene : Scene
    settings : NelderMeadSettings, optional
        Defaults: a reduced model of 3 elements at h = 0.5 s.
    quiet : bool
        No progress bar.
    verbose : bool
        Accepted for a uniform interface: Nelder-Mead has no log beyond its progress bar.
    """
    check_verbosity(quiet, verbose)
    started = time.perf_counter()
    settings = settings or NelderMeadSettings(elements=3, step=0.5)
    outcome = solve_nelder_mead(scene, settings, quiet=quiet)
    # A capped search is verified too (the paper's method usually stops at its cap); it stays
    # success = False.
    trajectory, reason = _verify(scene, outcome.control, outcome.parameters, quiet)
    omega = trajectory.omega if trajectory is not None else float("nan")
    return OcpResult(
        method="nelder-mead",
        parameters=outcome.parameters,
        control=f"spline({outcome.control.size})",
        trajectory=trajectory,
        omega=omega,
        omega_model=outcome.objective,
        success=outcome.success and reason is None,
        status=_nelder_mead_status(outcome, reason),
        iterations=outcome.iterations,
        evaluations=outcome.evaluations,
        wall_time=time.perf_counter() - started,
        build_time=0.0,
        solve_time=outcome.solve_time,
        function_time=outcome.solve_time,
        history=outcome.history,
        refinements=[omega],
    )


def optimize(
    scene,
    method: str = "ipopt",
    settings=None,
    quiet: bool = False,
    verbose: bool = False,
    **kwargs,
) -> OcpResult:
    """Optimise the winch angle of a scene.

    Parameters
    ----------
    scene : Scene
    method : str
        ``"ipopt"`` (direct shooting) or ``"nelder-mead"`` (the paper's method).
    settings : IpoptSettings or NelderMeadSettings, optional
    quiet : bool
        Print nothing at all.
    verbose : bool
        IPOPT's full log (by default, one progress line per iteration); not with ``quiet``.
    **kwargs
        Passed on (``refinements`` for IPOPT).

    Returns
    -------
    OcpResult
        Check ``success``: a failed solve is returned with ``success = False`` and the solver's
        status, never as an answer.
    """
    if method == "ipopt":
        return optimize_ipopt(scene, settings, quiet=quiet, verbose=verbose, **kwargs)
    if method == "nelder-mead":
        return optimize_nelder_mead(scene, settings, quiet=quiet, verbose=verbose)
    raise ValueError(f"method = {method!r}: must be 'ipopt' or 'nelder-mead'")
