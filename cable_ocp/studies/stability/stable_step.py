"""The largest stable RK4 step of one model, by bisection in ``log h``."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from cable_ocp.drive.drive import Drive
from cable_ocp.model.cable import CableModel
from cable_ocp.simulation.integrate import SimulationError
from cable_ocp.simulation.run import simulate
from cable_ocp.simulation.stability import linearised_step
from cable_ocp.simulation.statics import equilibrium
from cable_ocp.simulation.trajectory import Trajectory
from cable_ocp.studies.convergence import end_difference
from cable_ocp.studies.stability.push import pushed_scene

# A twist angle beyond this (rad) marks a torsional blow-up: the push exerts no torque.
TWIST_LIMIT = math.pi
# Random initial twist (rad) of torsion models, so that an unstable torsional mode can grow.
TWIST_SEED = 1e-6


@dataclass(frozen=True)
class StepSearch:
    """How the largest stable step of a model is searched: its runs, and where the search stops.

    Attributes
    ----------
    duration : float, s
        Shortest run; see :func:`run_length` for ``min_steps``.
    min_steps : int
        Fewest steps of a run (:func:`run_length`).
    resolution : float
        Largest ratio ``unstable_step / step`` at the end (> 1).
    tolerance : float, m
        Bond residual that stops a run. The scene's own (0.1 mm for end_force) is an accuracy
        bound: at large steps the push alone exceeds it, and so would 1 cm at n = 5, so the
        search would measure accuracy, not stability. A blow-up passes any bound within a few
        steps; whether the stable run is also accurate is ``quarter_step_difference``.
    linearised_samples : int
        States of the stable run (evenly spaced, first and last included) at which
        :func:`linearised_step` is evaluated; the smallest is reported. The push raises the
        tension, and with it the frequencies, above those of the equilibrium.
    """

    duration: float = 10.0
    min_steps: int = 200
    resolution: float = 1.1
    tolerance: float = 1.0
    linearised_samples: int = 5

    def __post_init__(self):
        if not self.resolution > 1:
            raise ValueError(f"StepSearch.resolution = {self.resolution!r}: must be > 1")


@dataclass(frozen=True)
class StableStep:
    """The largest stable RK4 step of one model, found by bisection in ``log h``.

    Attributes
    ----------
    elements : int
        ``n``.
    torsion : bool
        Whether the model has torsion (6 DOF per element).
    step : float, s
        Largest step found stable: its run completes.
    unstable_step : float, s
        Smallest step found unstable (``step < unstable_step <= resolution * step``).
    duration : float, s
        Length of the run at ``step``.
    runs : int
        Runs made (bracketing and bisection).
    quarter_step_difference : float, m
        ``max_t |r_E(step) - r_E(step / 4)|``: small if the stable run is also accurate.
    end_excursion : float, m
        Largest distance of the end from its start in the run at ``step / 4``.
    failure : str
        Why the run at ``unstable_step`` is unstable.
    linearised_step : float, s
        Largest step at which RK4 is stable for the linearisations at states of the run at
        ``step`` (the smallest over the states sampled).
    compiled : bool
        Whether the runs used the model compiled to C.
    wall_time : float, s
        Of the whole search.
    """

    elements: int
    torsion: bool
    step: float
    unstable_step: float
    duration: float
    runs: int
    quarter_step_difference: float
    end_excursion: float
    failure: str
    linearised_step: float
    compiled: bool
    wall_time: float


def run_length(step: float, duration: float, min_steps: int) -> float:
    """Duration of a stability run (s): at least ``duration`` and ``min_steps`` steps of ``step``.

    Just above the RK4 limit a mode grows by a factor of about 1.2-2 per step, so ``min_steps``
    steps take rounding noise beyond the bond tolerance even where ``duration`` holds few steps.
    """
    return max(math.ceil(duration / step - 1e-9), min_steps) * step


class _Runner:
    """Runs of one model from its equilibrium at any step (model and equilibrium built once).

    Torsion models get a random twist of ``twist_seed`` rad per element: the push exerts no
    torque, so without a seed the twist stays exactly zero and an unstable torsional mode never
    shows.
    """

    def __init__(self, scene, compiled: bool, quiet: bool, twist_seed: float):
        self.scene, self.compiled, self.quiet = scene, compiled, quiet
        self.model = CableModel.from_scene(scene)
        self.drive = Drive.from_scene(scene)
        self.x0 = equilibrium(self.model, self.drive).state
        if scene.model.torsion:
            twist = self.model.twist_angle_index()
            rng = np.random.default_rng(0)
            self.x0[twist] += twist_seed * rng.standard_normal(self.x0[twist].size)

    def run(self, step: float, duration: float, output_every: int = 1) -> Trajectory:
        """The run at ``step`` over ``duration`` (raises :class:`SimulationError`)."""
        local = self.scene.updated(
            {
                "numerics.step": step,
                "numerics.duration": duration,
                "numerics.output_every": output_every,
            }
        )
        return simulate(
            local, model=self.model, initial_state=self.x0, quiet=self.quiet, compiled=self.compiled
        )

    def attempt(self, step: float, duration: float) -> Trajectory | str:
        """The run at ``step``, or why it is unstable.

        Unstable: :class:`SimulationError`, or a twist angle beyond :data:`TWIST_LIMIT`. The twist
        does not move the element axes, so a torsional blow-up leaves the bonds intact and stays
        finite for many steps: the integrator's own checks do not see it.
        """
        try:
            run = self.run(step, duration)
        except SimulationError as error:
            return str(error)
        if self.scene.model.torsion:
            twist = np.abs(run.states[:, self.model.twist_angle_index()]).max(axis=1)
            beyond = twist > TWIST_LIMIT
            if beyond.any():
                k = int(np.argmax(beyond))
                return (
                    f"twist angle {twist[k]:.3g} rad beyond {TWIST_LIMIT:g} rad at "
                    f"t = {run.time[k]:.6g} s with step h = {step:g} s (torsional mode unstable)"
                )
        return run


def largest_stable_step(
    scene,
    elements: int,
    torsion: bool,
    first_step: float | None = None,
    search: StepSearch | None = None,
    twist_seed: float = TWIST_SEED,
    compiled: bool = False,
    quiet: bool = True,
) -> StableStep:
    """Largest RK4 step at which a pushed run of the scene stays stable (bisection in ``log h``).

    A run is stable if :func:`cable_ocp.simulation.run.simulate` completes without
    :class:`SimulationError` (non-finite state, or a bond residual beyond ``search.tolerance``)
    and, with torsion, no twist angle exceeds :data:`TWIST_LIMIT`. From ``first_step`` the step is
    doubled (or halved) until a stable and an unstable step bracket the limit; the bracket is then
    bisected in ``log h`` until its ratio is below ``search.resolution``. The stable end is
    compared with a run at a quarter of its step, so that a run that completes but is wrong shows
    up.

    Parameters
    ----------
    scene : Scene
        Usually ``end_force``; it is pushed from ``t = 0`` (:func:`pushed_scene`).
    elements : int
        ``n`` of the model.
    torsion : bool
        Whether the model has torsion (6 DOF per element).
    first_step : float, optional, s
        Where the search starts (the scene's step by default).
    search : StepSearch, optional
        The runs tried and where the bisection stops (by default ``StepSearch()``).
    twist_seed : float, rad
        Random initial twist per element of a torsion model (see :class:`_Runner`).
    compiled : bool
        Integrate with the model compiled to C (for n >= 10 the right-hand side is compiled once
        for all steps; worth it when the runs are long).
    quiet : bool
        Print nothing.

    Returns
    -------
    StableStep
    """
    search = search or StepSearch()
    started = time.perf_counter()
    local = pushed_scene(scene, elements, torsion).updated(
        {"numerics.constraint_tolerance": search.tolerance}
    )
    runner = _Runner(local, compiled, quiet, twist_seed)
    trials: dict[float, Trajectory | str] = {}

    def stable(step: float) -> bool:
        trials[step] = runner.attempt(step, run_length(step, search.duration, search.min_steps))
        return not isinstance(trials[step], str)

    step = first_step or scene.numerics.step
    if stable(step):
        low, high = step, 2 * step
        while stable(high):
            low, high = high, 2 * high
    else:
        low, high = step / 2, step
        while not stable(low):
            low, high = low / 2, low
    while high / low > search.resolution:
        middle = math.sqrt(low * high)
        if stable(middle):
            low = middle
        else:
            high = middle
    coarse = trials[low]
    quarter = runner.run(low / 4, coarse.time[-1], output_every=4)
    samples = np.linspace(0, coarse.time.size - 1, search.linearised_samples).round().astype(int)
    return StableStep(
        elements=elements,
        torsion=torsion,
        step=low,
        unstable_step=high,
        duration=float(coarse.time[-1]),
        runs=len(trials),
        quarter_step_difference=end_difference(coarse, quarter),
        end_excursion=float(np.linalg.norm(quarter.end - quarter.end[0], axis=1).max()),
        failure=trials[high],
        linearised_step=min(
            linearised_step(runner.model, x, u)
            for x, u in zip(coarse.states[samples], coarse.inputs[samples], strict=True)
        ),
        compiled=compiled,
        wall_time=time.perf_counter() - started,
    )
