"""The front door for optimal winch control: ``optimize(scene, method="ipopt" | "nelder-mead")``.

Whatever model the optimiser works on, the result's Omega comes from a simulation of the scene's
own model with the optimised winch angle. With a reduced optimisation model, IPOPT's answer is
refined by model correction: the NLP is solved again with the bias ``b = e_full - e_reduced`` of the
last winch profile added to its clearance error, so the reduced model steers while the full model
keeps score (DESIGN.md §5, "reduced models for optimisation").
"""

from __future__ import annotations

import json
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from cable_ocp.integrate import SimulationError
from cable_ocp.nelder_mead import NelderMeadSettings, solve_nelder_mead
from cable_ocp.ocp import IpoptSettings, MultipleShooting
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
        The scene's full model driven by the optimised winch; None only for a failed solve whose
        last iterate cannot even be simulated.
    omega : float, m
        Omega (eq. 39) of ``trajectory`` (NaN without one).
    omega_model : float, m
        Omega on the optimisation model, as the optimiser saw it.
    success : bool
        False when the solver did not converge (or ran out of evaluations).
    status : str
        The solver's own status message.
    iterations : int
    evaluations : int
        Objective evaluations (Nelder-Mead) or NLP objective evaluations (IPOPT).
    wall_time : float, s
        Everything, including building and verification.
    build_time : float, s
        Building the NLP (symbolic work), reported apart.
    solve_time : float, s
        Time inside the solver(s).
    function_time : float, s
        Of ``solve_time``, the part spent evaluating NLP functions and derivatives (IPOPT).
    history : list of float
        Objective per iteration (IPOPT: Omega^2 on the optimisation model, m^2) or best Omega per
        evaluation (Nelder-Mead, m).
    refinements : list of float
        Verified Omega after each solve (m); more than one entry with model correction.
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

    def save(self, folder: str | Path) -> None:
        """Write ``result.json``, ``result.npz`` and the trajectory into ``folder``."""
        folder = Path(folder)
        folder.mkdir(parents=True, exist_ok=True)
        if self.trajectory is not None:
            self.trajectory.save(folder / "trajectory")
        meta = {k: v for k, v in asdict(self).items() if k not in ("parameters", "trajectory")}
        (folder / "result.json").write_text(json.dumps(meta, indent=1))
        np.savez(folder / "result.npz", parameters=self.parameters)

    @classmethod
    def load(cls, folder: str | Path) -> OcpResult:
        """Read a result written by :meth:`save`."""
        folder = Path(folder)
        meta = json.loads((folder / "result.json").read_text())
        with np.load(folder / "result.npz") as data:
            parameters = data["parameters"]
        has_trajectory = (folder / "trajectory.npz").exists()
        trajectory = Trajectory.load(folder / "trajectory") if has_trajectory else None
        return cls(parameters=parameters, trajectory=trajectory, **meta)


def _verify(scene, control, parameters, quiet, solved: bool = True):
    """Simulate the scene's model with the winch; None if a failed solve's iterate cannot run."""
    try:
        return simulate(scene, winch=control.angle_function(parameters), quiet=quiet)
    except (SimulationError, ValueError):
        if solved:
            raise
        return None


def optimize_ipopt(
    scene, settings: IpoptSettings | None = None, refinements: int = 3, quiet: bool = False
) -> OcpResult:
    """Direct multiple shooting + IPOPT, verified (and refined) on the scene's model.

    Parameters
    ----------
    scene : Scene
    settings : IpoptSettings, optional
        Defaults: a reduced model of 3 elements at h = 0.5 s, 42 intervals, Hermite control.
    refinements : int
        Model-correction solves after the first (0 disables them); they stop early when the
        verified Omega stops improving. Ignored when the optimisation model is the scene's own.
    quiet : bool
    """
    started = time.perf_counter()
    settings = settings or IpoptSettings(elements=3, step=0.5)
    problem = MultipleShooting(scene, settings, quiet=quiet)
    outcome = problem.solve(problem.first_guess())
    best_outcome = outcome
    best = _verify(scene, problem.control, outcome.parameters, quiet, outcome.success)
    verified = [best.omega if best is not None else float("nan")]
    outcomes = [outcome]
    reduced = (
        problem.model.spec.elements != scene.model.elements or problem.step != scene.numerics.step
    )
    for _ in range(refinements if reduced else 0):
        if not outcome.success:
            break
        full_error = np.interp(problem.grid, best.time, best.clearance_error)
        model_error = problem.clearance(problem.simulate(best_outcome.parameters))
        outcome = problem.solve(best_outcome.parameters, full_error - model_error)
        outcomes.append(outcome)
        trial = _verify(scene, problem.control, outcome.parameters, quiet, outcome.success)
        if trial is None or not outcome.success or trial.omega >= best.omega:
            verified.append(float("nan") if trial is None else trial.omega)
            break
        verified.append(trial.omega)
        gain = trial.omega / best.omega
        best_outcome, best = outcome, trial
        if gain > SMALL_GAIN:
            break
    failed = [o for o in outcomes if not o.success]
    status = failed[0].status if failed else best_outcome.status
    return OcpResult(
        method="ipopt",
        parameters=best_outcome.parameters,
        control=f"{settings.control}({problem.control.size})",
        trajectory=best,
        omega=best.omega if best is not None else float("nan"),
        omega_model=float(np.sqrt(max(best_outcome.objective, 0.0))),
        success=not failed,
        status=status,
        iterations=sum(o.iterations for o in outcomes),
        evaluations=sum(o.iterations for o in outcomes) + len(outcomes),
        wall_time=time.perf_counter() - started,
        build_time=problem.build_time,
        solve_time=sum(o.solve_time for o in outcomes),
        function_time=sum(o.function_time for o in outcomes),
        history=[v for o in outcomes for v in o.history],
        refinements=verified,
    )


def optimize_nelder_mead(
    scene, settings: NelderMeadSettings | None = None, quiet: bool = False
) -> OcpResult:
    """The paper's Nelder-Mead over the spline knots, verified on the scene's model."""
    started = time.perf_counter()
    settings = settings or NelderMeadSettings(elements=3, step=0.5)
    outcome = solve_nelder_mead(scene, settings, quiet=quiet)
    trajectory = _verify(scene, outcome.control, outcome.parameters, quiet, outcome.success)
    return OcpResult(
        method="nelder-mead",
        parameters=outcome.parameters,
        control=f"spline({outcome.control.size})",
        trajectory=trajectory,
        omega=trajectory.omega if trajectory is not None else float("nan"),
        omega_model=outcome.objective,
        success=outcome.success,
        status=outcome.message,
        iterations=outcome.iterations,
        evaluations=outcome.evaluations,
        wall_time=time.perf_counter() - started,
        build_time=0.0,
        solve_time=outcome.solve_time,
        function_time=outcome.solve_time,
        history=outcome.history,
        refinements=[trajectory.omega if trajectory is not None else float("nan")],
    )


def optimize(
    scene, method: str = "ipopt", settings=None, quiet: bool = False, **kwargs
) -> OcpResult:
    """Optimise the winch angle of a scene.

    Parameters
    ----------
    scene : Scene
    method : str
        ``"ipopt"`` (multiple shooting) or ``"nelder-mead"`` (the paper's method).
    settings : IpoptSettings or NelderMeadSettings, optional
    quiet : bool
        No solver log or progress bar.
    **kwargs
        Passed on (``refinements`` for IPOPT).

    Returns
    -------
    OcpResult
        Check ``success``: a failed solve is returned with ``success = False`` and the solver's
        status, never as an answer.
    """
    if method == "ipopt":
        return optimize_ipopt(scene, settings, quiet=quiet, **kwargs)
    if method == "nelder-mead":
        return optimize_nelder_mead(scene, settings, quiet=quiet)
    raise ValueError(f"method = {method!r}: must be 'ipopt' or 'nelder-mead'")
