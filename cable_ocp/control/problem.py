"""The winch-control problem of a scene, stated once and independent of how it is solved.

A :class:`WinchProblem` holds what every solver and the verification share: the optimisation
model (the scene's, or a reduced one), its RK4 step and grid, the drive with the winch locked, the
initial equilibrium, the winch parametrisation with its bounds, and the objective Omega (eq. 39:
the RMS of the clearance error, CONVENTIONS.md §5). IPOPT (:mod:`cable_ocp.control.ipopt`)
transcribes it into an NLP, Nelder-Mead (:mod:`cable_ocp.control.nelder_mead`) searches it
directly, and :meth:`WinchProblem.verify` scores a profile on the scene's own model. Every solver
reports a :class:`SolverOutcome`.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from cable_ocp.control.hermite_nodes import HermiteNodes
from cable_ocp.control.parameters import ProblemParameters
from cable_ocp.drive import winch
from cable_ocp.drive.bounds import LinearBounds, angle_bounds
from cable_ocp.drive.controls import HermiteIntervals, KnotSpline
from cable_ocp.drive.drive import Drive
from cable_ocp.model.cable import CableModel
from cable_ocp.simulation.integrate import integrate, stage_inputs, step_count
from cable_ocp.simulation.landing_reference import reference_error
from cable_ocp.simulation.seabed import (
    bathymetry,
    clearance_error,
    clearance_reference,
    rms_objective,
)
from cable_ocp.simulation.statics import starting_state

# Bond residual allowed in the runs of the optimisation model, as a share of its element length
# (1 cm on the 100 m elements of the default 3-element model): a coarse model only has to be
# close, not exact.
GUESS_TOLERANCE = 1e-4
Control = KnotSpline | HermiteIntervals | HermiteNodes


@dataclass(frozen=True, eq=False)
class WinchProblem:
    """Minimise Omega of a scene over the parameters of a winch-angle profile.

    Attributes
    ----------
    scene : Scene
        Its own model scores the result (:meth:`verify`).
    model : CableModel
        The optimisation model: the scene's or one with fewer elements.
    step : float, s
        RK4 step of the optimisation model.
    grid : array, s
        The RK4 times ``0, h, ..., T``.
    drive : Drive
        The optimisation model's drive with the winch locked.
    x0 : array
        Its equilibrium at t = 0, where every run starts.
    control : KnotSpline, HermiteIntervals or HermiteNodes
        The winch angle as a linear function of the parameters.
    low, high : float, rad
        Bounds of the angle (and of each parameter that is an angle).
    bounds : LinearBounds
        The winch bounds (angle, rate, acceleration, top-element length) as linear constraints on
        the parameters, held between the RK4 samples too.
    heave_feedforward : bool
        The scene heaves and the profile is optimised on top of paying the heave out (eq. 38):
        ``scene`` is then the user's scene with ``top.heave.compensation`` on, which is what
        the verification simulates.
    """

    scene: object
    model: CableModel
    step: float
    grid: np.ndarray
    drive: Drive
    x0: np.ndarray
    control: Control
    low: float
    high: float
    bounds: LinearBounds
    heave_feedforward: bool = False

    @classmethod
    def from_scene(
        cls,
        scene,
        control: Control,
        elements: int | None = None,
        step: float | None = None,
        compiled: bool = False,
    ) -> WinchProblem:
        """The problem of a scene with a winch parametrisation, on a model of ``elements``.

        Parameters
        ----------
        scene : Scene
        control : KnotSpline or HermiteIntervals
        elements : int, optional
            Elements of the optimisation model (None: the scene's).
        step : float, optional, s
            Its RK4 step (None: the scene's); it must divide ``numerics.duration``.
        compiled : bool
            Find the starting equilibrium on the compiled model
            (:func:`cable_ocp.simulation.statics.equilibrium`: the same tolerance).

        The open loop knows the vessel's whole motion: a heave that the scene does not
        compensate is paid out by eq. 38 as a feedforward, and the control optimises the slow
        profile on top (the winch bounds apply to the sum).
        """
        scene, feedforward = cls.open_loop_scene(scene)
        step = step or scene.numerics.step
        duration = scene.numerics.duration
        return cls._over(scene, control, elements, step, duration, feedforward, compiled)

    @staticmethod
    def open_loop_scene(scene):
        """The scene the open loop simulates, and whether it pays a heave out (eq. 38).

        A heave that the scene does not compensate is paid out as a feedforward: the scene is
        then the user's with ``top.heave.compensation`` on.
        """
        feedforward = scene.top.heave is not None and not scene.top.heave.compensation
        if feedforward:
            scene = scene.updated({"top.heave.compensation": True})
        return scene, feedforward

    @classmethod
    def receding(cls, scene, nodes: np.ndarray, elements: int, step: float) -> WinchProblem:
        """The problem over one horizon of a receding-horizon controller (a closed loop).

        The control is a free-start Hermite angle on the plan's ``nodes`` (its node 0 is where
        the winch is when the solve starts): :class:`HermiteIntervals` where they are equally
        spaced, :class:`HermiteNodes` otherwise. The bounds hold between the samples as in the
        open loop. The defaults of :meth:`parameter_values` are the scene's first horizon; a
        controller sets them from its estimate and forecasts at every sample.

        Parameters
        ----------
        scene : Scene
        nodes : array, s
            The plan's node times, 0 to the horizon (:attr:`MpcSettings.plan_nodes`), each a
            whole multiple of ``step``.
        elements : int
            Elements of the controller's model.
        step : float, s
        """
        nodes = np.asarray(nodes, dtype=float)
        horizon, intervals = float(nodes[-1]), nodes.size - 1
        if np.allclose(nodes, np.linspace(0.0, horizon, intervals + 1), rtol=0, atol=1e-9):
            control = HermiteIntervals(horizon, intervals, free_start=True)
        else:
            control = HermiteNodes(nodes, free_start=True)
        return cls._over(scene, control, elements, step, horizon)

    @classmethod
    def _over(
        cls,
        scene,
        control: Control,
        elements: int | None,
        step: float,
        horizon: float,
        feedforward: bool = False,
        compiled: bool = False,
    ) -> WinchProblem:
        """The problem on ``[0, horizon]``: the model, its locked drive, start and bounds."""
        grid = np.arange(step_count(horizon, step) + 1) * step
        model = CableModel.from_scene(scene, elements)
        drive = Drive.from_scene(scene, winch.locked, elements=model.spec.elements)
        low, high = angle_bounds(scene)
        return cls(
            scene=scene,
            model=model,
            step=step,
            grid=grid,
            drive=drive,
            x0=starting_state(model, drive, compiled=compiled),
            control=control,
            low=low,
            high=high,
            bounds=LinearBounds.build(scene, control, grid),
            heave_feedforward=feedforward,
        )

    def with_control(self, control: Control) -> WinchProblem:
        """The problem on the same model and grid with another control (its own bound rows)."""
        bounds = self.bounds.on_control(self.scene, control, self.grid)
        return replace(self, control=control, bounds=bounds)

    @property
    def duration(self) -> float:
        """The horizon (s): the scene's ``numerics.duration`` in the open loop."""
        return float(self.grid[-1])

    def parameter_values(self) -> ProblemParameters:
        """The named parameters from the scene: its start, top motion and end force."""
        inputs = stage_inputs(self.drive, self.grid[:-1], self.step)
        reference = clearance_reference(self.scene.seabed, self.x0)
        values = ProblemParameters.from_stage_inputs(self.x0, inputs, reference)
        return replace(values, bias=self.landing_bias())

    def landing_bias(self) -> np.ndarray:
        """The bias of :meth:`parameter_values` (m): ``-e_ref`` on the grid, zero off a landing.

        A landing's error is the deviation from its reference.
        """
        start_error = float(clearance_error(self.scene.seabed, self.x0[None, :3])[0])
        return -reference_error(self.scene, self.grid, start_error)

    @property
    def reduced(self) -> bool:
        """Whether the optimisation model differs from the scene's (elements or step)."""
        return (
            self.model.spec.elements != self.scene.model.elements
            or self.step != self.scene.numerics.step
        )

    def drive_with(self, parameters: np.ndarray) -> Drive:
        """The optimisation model's drive under the winch profile of ``parameters``."""
        return Drive.from_scene(
            self.scene, self.control.angle_function(parameters), elements=self.model.spec.elements
        )

    def simulate(self, parameters: np.ndarray, compiled: bool = False) -> np.ndarray:
        """States of the optimisation model on the grid under a winch profile (array (k, nx)).

        Raises :class:`cable_ocp.simulation.integrate.SimulationError` when the run blows up or
        leaves its bonds by more than :data:`GUESS_TOLERANCE` of an element's length.
        """
        run = integrate(
            self.model,
            self.x0,
            self.drive_with(parameters),
            self.duration,
            self.step,
            tolerance=GUESS_TOLERANCE * self.model.spec.segment_length,
            compiled=compiled,
        )
        return run.states

    def clearance(self, states: np.ndarray) -> np.ndarray:
        """Clearance error e(t) (m) of states of the optimisation model.

        Off a bathymetry grid the seabed is held at the grid's edge, as in the transcriptions'
        symbolic error: the optimisation model's runs (the first guess, a trial) may leave the
        grid; only the verified profile must stay on it. On a landing, the deviation from its
        reference (:mod:`~cable_ocp.simulation.landing_reference`).
        """
        positions = np.array(states[:, :3], dtype=float)
        grid = bathymetry(self.scene.seabed)
        if grid is not None:
            positions[:, 0] = np.clip(positions[:, 0], grid.x[0], grid.x[-1])
            positions[:, 1] = np.clip(positions[:, 1], grid.y[0], grid.y[-1])
        error = clearance_error(self.scene.seabed, positions)
        return error - reference_error(self.scene, self.grid[: error.size], error[0])

    def omega(self, states: np.ndarray) -> float:
        """Omega (eq. 39, m) of states of the optimisation model on the grid."""
        return rms_objective(self.grid, self.clearance(states))

    def first_guess(self, compiled: bool = False) -> np.ndarray:
        """Parameters that pay out what the locked winch lets the end rise (rad).

        A least-squares fit of ``phi = e_locked(t) / r_D`` (clipped to the angle bounds) by the
        control; ``compiled`` runs the locked winch on the compiled model.
        """
        rise = self.clearance(self.simulate(np.zeros(self.control.size), compiled))
        target = np.clip(rise / self.scene.winch.drum_radius, self.low, self.high)
        basis = self.control.basis(self.grid)[0]
        guess, *_ = np.linalg.lstsq(basis, target, rcond=None)
        return guess


@dataclass(frozen=True)
class SolverOutcome:
    """What a solver returned for a :class:`WinchProblem`, before verification.

    Attributes
    ----------
    parameters : array
        Winch parameters (rad, rad/s).
    status : str
        The solver's own status (IPOPT's return status, SciPy's message) or why it failed.
    success : bool
        Whether the solver reports convergence (and, for Nelder-Mead, a profile within bounds
        that simulated).
    iterations, evaluations : int
        Iterations, and objective evaluations (IPOPT: one per iteration and one to start).
    omega : float, m
        Omega on the optimisation model, as the solver saw it.
    build_time, compile_time, solve_time, function_time : float, s
        Building the transcription (compiling included), compiling C alone (0 on a cache hit),
        inside the solver, and of that evaluating the objective and its derivatives.
    history : list of float
        IPOPT and Gauss-Newton: Omega^2 (m^2) at each iteration; Nelder-Mead: the best Omega (m)
        after each evaluation.
    states : array (k, nx) or None
        The optimisation model's run under ``parameters``, when the solver has it (Gauss-Newton):
        it spares a simulation for the model correction.
    """

    parameters: np.ndarray
    status: str
    success: bool
    iterations: int
    evaluations: int
    omega: float
    build_time: float
    compile_time: float
    solve_time: float
    function_time: float
    history: list[float]
    states: np.ndarray | None = None


class ProblemSolver:
    """A solver of a :class:`WinchProblem`, built once and solved as often as needed.

    The contract is :mod:`cable_ocp.control.solvers`'; each solver implements :meth:`run`.
    """

    build_time = compile_time = 0.0

    def solve(
        self,
        values: ProblemParameters,
        guess: np.ndarray,
        fixed: dict[int, float] | None = None,
        lower: np.ndarray | None = None,
        upper: np.ndarray | None = None,
    ) -> SolverOutcome:
        """Solve from the winch parameters ``guess`` (rad, rad/s) under the parameter values.

        ``fixed`` pins winch parameters (index to value); ``lower``/``upper`` replace the bound
        rows' own limits (a closed loop narrows the angle range). What the solver does is its
        :meth:`run`'s.
        """
        return self.run(values, np.array(guess, dtype=float), dict(fixed or {}), lower, upper)

    def run(self, values, guess, fixed, lower, upper) -> SolverOutcome:
        """:meth:`solve` with its arguments made explicit (``fixed`` a dict, ``guess`` a copy)."""
        raise NotImplementedError
