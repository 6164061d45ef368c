"""Reference runs of a closed loop: its plant under the winch locked, or the open-loop optimum.

A closed loop is judged against what the winch does without it, on the same plant and time grid
(the scene's own model at its step, the soft limiter of the loop): ``"locked"``, and
``"open-loop"``, the optimum of :func:`cable_ocp.optimize` on the scene without its heave,
applied as it is and, on a heaving scene, with the heave paid out by eq. 38
(``"open-loop + heave feedback"``). :func:`reference_runs` runs them after the loop.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cable_ocp.control.closed_loop.plant import Plant, plant_run
from cable_ocp.control.closed_loop.result import MpcResult
from cable_ocp.control.interrupts import interrupt_here
from cable_ocp.control.optimization import optimize
from cable_ocp.control.shooting import make_control, resolved
from cable_ocp.control.solvers import ocp_settings
from cable_ocp.drive.drive import Drive
from cable_ocp.simulation.integrate import SimulationError
from cable_ocp.simulation.trajectory import Trajectory

REFERENCES = ("locked", "open-loop")


@dataclass(frozen=True)
class ReferenceRuns:
    """Reference runs of a closed loop's plant, on the loop's time grid.

    Attributes
    ----------
    runs : dict of str to Trajectory
        Each run that went to the end, by name (``"locked"``, ``"open-loop"``, ``"open-loop +
        heave feedback"``), as the closed loop's own run (``MpcResult.trajectory``).
    notes : list of str
        Each run left out, and why.
    """

    runs: dict[str, Trajectory]
    notes: list[str]

    @property
    def omegas(self) -> dict[str, float]:
        """Omega (eq. 39) of each run by name, m."""
        return {name: run.omega for name, run in self.runs.items()}


def reference_runs(scene, result: MpcResult, names=("locked",)) -> ReferenceRuns:
    """Run the plant of a closed loop under each reference winch of ``names``.

    Parameters
    ----------
    scene : Scene
        The plant's scene (the loop's).
    result : MpcResult
        The loop: its time grid, winch range and soft limiter band (``settings``).
    names : sequence of str
        Of :data:`REFERENCES`.

    Returns
    -------
    ReferenceRuns
        None of them when the loop stopped early; a run whose plant fails, or an open-loop
        optimum that fails, is left out with a note.

    Raises
    ------
    ValueError
        A name that is not of :data:`REFERENCES`.
    """
    unknown = set(names) - set(REFERENCES)
    if unknown:
        raise ValueError(
            f"references = {tuple(names)}: each must be one of {', '.join(REFERENCES)}"
        )
    time_grid = result.time
    plant = Plant(scene, result.angle_range, result.setting("limiter_band"))
    runs, notes = {}, []

    def run(name, angle):
        try:
            runs[name] = _run_open(plant, angle, time_grid)
        except SimulationError as error:
            notes.append(f"reference {name!r} left out: its plant run failed ({error})")

    if time_grid[-1] < scene.numerics.duration:
        notes.append("no reference runs: the loop stopped early")
    else:
        if "locked" in names:
            run("locked", lambda t: tuple(np.zeros((3, np.size(t)))))
        if "open-loop" in names:
            _open_loop(scene, run, notes)
    return ReferenceRuns(runs, notes)


def _open_loop(scene, run, notes: list[str]) -> None:
    """The open-loop optimum of the calm scene, as it is and with the heave paid out."""
    # The open loop knows no heave at all: neither the sine nor the sea state.
    calm = scene.updated({"top.heave": None})
    try:
        # The settings optimize() derives, fixed here: the profile's control needs them.
        settings, _ = resolved(calm, ocp_settings())
        result = optimize(calm, settings=settings, quiet=True)
    except (ValueError, RuntimeError) as error:  # the derivation's locked run, say
        notes.append(f"reference 'open-loop' left out: {error}")
        return
    if not result.success:
        notes.append(f"reference 'open-loop' left out: {result.status}")
        return
    profile = make_control(calm, settings).angle_function(result.parameters)
    run("open-loop", profile)
    if scene.top.has_heave:
        # The same profile with the heave paid out by eq. 38 (the drive's compensation).
        compensated = scene.updated({"top.heave.compensation": True})
        run("open-loop + heave feedback", Drive.from_scene(compensated, profile).winch_angle)


def _run_open(plant: Plant, angle, time_grid: np.ndarray) -> Trajectory:
    """The plant's run under a fixed angle history (no controller).

    Raises SimulationError when the plant fails under it.
    """
    x = plant.initial_state(plant.apply(angle, np.zeros(1)))
    interrupt_here("reference run")
    states, inputs, applied = plant.advance(x, 0.0, time_grid.size - 1, angle)
    return plant_run(plant, time_grid, states, inputs, applied.angle)
