"""The front door for simulation: ``simulate(scene, winch=...)`` returns a :class:`Trajectory`."""

from __future__ import annotations

from dataclasses import fields, replace

import numpy as np

from cable_ocp.drive.bounds import BOUND_TOLERANCE
from cable_ocp.drive.drive import Drive
from cable_ocp.model.cable import CableModel, spec_from_scene
from cable_ocp.model.layout import INPUTS
from cable_ocp.scene.given import scene_given
from cable_ocp.scene.rules import finite_array
from cable_ocp.simulation.budget import check_simulation_memory
from cable_ocp.simulation.drum_range import beyond
from cable_ocp.simulation.integrate import TIME_BLOCK, integrate, step_times
from cable_ocp.simulation.landing_reference import reference_error
from cable_ocp.simulation.line_run import simulate_line
from cable_ocp.simulation.line_trajectory import LineTrajectory
from cable_ocp.simulation.outputs import output_trajectory, run_outputs
from cable_ocp.simulation.seabed import (
    check_on_grid,
    check_start,
    clearance_error,
    rms_objective,
)
from cable_ocp.simulation.statics import starting_state
from cable_ocp.simulation.trajectory import Trajectory
from cable_ocp.simulation.winch_input import WinchSpec, winch_function

# Largest share of the line out that the graded mesh's top element may carry (check_top_length).
TOP_SHARE = 1 / 3


def check_top_length(scene, drive: Drive, times: np.ndarray) -> None:
    """Raise before integrating if the winch takes the top element out of its length range.

    A length outside by at most ``winch.drum_radius * BOUND_TOLERANCE`` (the angle tolerance of
    :mod:`cable_ocp.drive.bounds` as a length, m) counts as within it. The inputs are evaluated
    :data:`TIME_BLOCK` times at a time.

    Parameters
    ----------
    scene : Scene
    drive : Drive
    times : array (k,), s
    """
    for first in range(0, len(times), TIME_BLOCK):
        _check_top_length(scene, drive, times[first : first + TIME_BLOCK])


def _check_top_length(scene, drive: Drive, times: np.ndarray) -> None:
    length = drive.inputs(times)[INPUTS.top_length]
    if not np.isfinite(length).all():
        k = int(np.argmin(np.isfinite(length)))
        raise ValueError(
            f"the winch gives the angle {length[k]} at t = {times[k]:.6g} s: the winch function "
            "must return finite angles (rad) over the whole run"
        )
    low, high = scene.winch.top_length_min, scene.winch.top_length_max
    tolerance = scene.winch.drum_radius * BOUND_TOLERANCE
    if high is None:
        check_rod(length, scene.cable.length + length - drive.top_length, times, tolerance)
        high = np.inf
    found = beyond(times, length, low, high, "sets the top element to", "m",
                   ("top_length_min", "top_length_max"), tolerance)  # fmt: skip
    if found:
        raise ValueError(f"{found}, by more than the tolerance {tolerance:.3g} m")


def check_rod(
    length: np.ndarray, line: np.ndarray, times: np.ndarray, tolerance: float = 0.0
) -> None:
    """Refuse a graded top element paid out to more than :data:`TOP_SHARE` of the line out.

    Without ``winch.top_length_max`` the graded mesh's top element grows by all the drum pays
    out: a rigid rod, not a rope, once it carries a large share of the line (measured: 300 m of
    drum range on ``paper_hill`` gave a 210 m rod, silently).

    Parameters
    ----------
    length : array (k,), m
        The top element's length.
    line : array (k,), m
        The line out then.
    times : array (k,), s
        When (for the message).
    tolerance : float, m
        How far beyond the share still counts as within it.

    Raises
    ------
    ValueError
        At the first time beyond the share, with the length, the line and the remedies.
    """
    over = length > TOP_SHARE * line + tolerance
    if over.any():
        k = int(np.argmax(over))
        raise ValueError(
            f"the winch pays the top element out to {length[k]:.4g} m at t = {times[k]:.6g} s, "
            f"{length[k] / line[k]:.0%} of the {line[k]:.4g} m of line out: one rigid rod, not a "
            f"rope (the graded mesh's top element may carry at most {TOP_SHARE:.0%} of the line). "
            "Pay out through [winch.line] (elements split off at the drum), or narrow "
            "winch.angle_max / set winch.top_length_max"
        )


def checked_state(state, size: int) -> np.ndarray:
    """``state`` as a float vector of ``size`` finite values, or ValueError naming what is wrong."""
    return finite_array(state, "initial_state", (size,), "the model's state")


def joints_and_tensions(
    model: CableModel, states: np.ndarray, inputs: np.ndarray, compiled: bool = False
) -> tuple[np.ndarray, np.ndarray]:
    """Joint positions (k, 3, n+2; m) and bond tensions ``|lambda_j|`` (k, n+1; N) of k states.

    The first two of :func:`run_outputs`.
    """
    joints, tensions, _ = run_outputs(model, states, inputs, compiled)
    return joints, tensions


def simulate(
    scene,
    winch: WinchSpec = None,
    model: CableModel | None = None,
    initial_state: np.ndarray | None = None,
    quiet: bool = True,
    compiled: bool = False,
) -> Trajectory | LineTrajectory:
    """Simulate a scene by RK4 from its static equilibrium.

    The run's physics (a rope that pushes, an end under an absolute seabed, a drum beyond
    ``[winch.angle_min, winch.angle_max]``) is checked after it: ``trajectory.success``,
    ``status`` and ``summary()`` say where and when (:mod:`cable_ocp.simulation.slack`); a run
    that fails it is returned, not raised. Its ``bond_residual`` is the largest bond residual
    that the integration checked (the health check of the run).

    Parameters
    ----------
    scene : Scene, str or path-like
        A scene, a scene file's path or a bundled scene's name.
    winch : None, array, callable or a result
        See :func:`winch_function`; locked by default.
    model : CableModel, optional
        A model built for the scene (built here if not given); it may have another number of
        elements than the scene.
    initial_state : array (model.state_size,), optional
        Defaults to the static equilibrium under the inputs at t = 0, moving as the top does
        then (:func:`~cable_ocp.simulation.statics.moving_with_the_top`: a heave starts at full
        speed); must be finite.
    quiet : bool
        No progress bar when true.
    compiled : bool
        Integrate with the model compiled to C (cached on disk; the first build compiles).

    Returns
    -------
    Trajectory or LineTrajectory
        A :class:`LineTrajectory` for a scene with ``[winch.line]`` (segment by segment).

    Raises
    ------
    ValueError
        Before integrating: a winch of the wrong length or not finite, a winch that takes the top
        element out of its length range, an ``initial_state`` of the wrong shape or not finite.
    OffGridError
        A :class:`~cable_ocp.simulation.integrate.SimulationError`: the end starts off the
        bathymetry grid or under the seabed (before integrating), or leaves the grid.
    """
    scene = scene_given(scene, "simulate")
    if scene.winch.line is not None:
        return _line_simulation(scene, winch, model, initial_state, quiet, compiled)
    numerics = scene.numerics
    if model is not None:
        check_model_fits(scene, model)
    check_simulation_memory(
        scene, model.spec.elements if model is not None else None, compiled=compiled
    )
    angle = winch_function(scene, winch)
    model = model or CableModel.from_scene(scene)
    drive = Drive.from_scene(scene, angle, elements=model.spec.elements)
    for times in step_times(numerics.duration, numerics.step):
        check_top_length(scene, drive, times)
    if initial_state is not None:
        initial_state = checked_state(initial_state, model.state_size)
    if initial_state is None:
        initial_state = starting_state(model, drive, compiled=compiled)
    x0 = initial_state
    check_start(scene.seabed, x0[:3])
    run = integrate(
        model,
        x0,
        drive,
        numerics.duration,
        numerics.step,
        output_every=numerics.output_every,
        tolerance=numerics.constraint_tolerance,
        quiet=quiet,
        compiled=compiled,
    )
    angle = drive.winch_angle(run.time)[0]
    trajectory = run_trajectory(scene, model, run.time, run.states, run.inputs, angle, compiled)
    return replace(trajectory, bond_residual=run.bond_residual)


def run_trajectory(
    scene,
    model: CableModel,
    time: np.ndarray,
    states: np.ndarray,
    inputs: np.ndarray,
    winch_angle: np.ndarray,
    compiled: bool = False,
) -> Trajectory:
    """The :class:`Trajectory` of a run of ``model`` on ``scene``.

    Its states and inputs at ``time`` (s), with the winch angle (rad) that drove it.

    Its joints and tensions are the model's outputs (:func:`run_outputs`), ``e(t)`` and
    Omega those of eq. 39 on the end's path (no Omega of a single point: NaN); on a fixed-``n``
    landing, ``e(t)`` is the deviation from the landing reference
    (:mod:`~cable_ocp.simulation.landing_reference`). Raises
    :class:`~cable_ocp.simulation.seabed.OffGridError` if the end left the bathymetry grid.
    """
    outputs = run_outputs(model, states, inputs, compiled)
    joints = outputs[0]
    check_on_grid(scene.seabed, joints[:, :, 0], time)
    error = clearance_error(scene.seabed, joints[:, :, 0])
    error = error - reference_error(scene, time, error[0])
    omega = rms_objective(time, error) if time.size > 1 else float("nan")
    return output_trajectory(scene, model, time, states, inputs, outputs, winch_angle, error, omega)


def check_model_fits(scene, model: CableModel) -> None:
    """Refuse a model built for another scene (its rope, payload, sea or numerics differ).

    A model may have another number of elements than the scene (a reduced model); everything
    else that fixes it (:class:`~cable_ocp.model.cable.ModelSpec`) must be the scene's.

    Raises
    ------
    TypeError
        ``model`` is not a :class:`~cable_ocp.model.cable.CableModel`.
    ValueError
        Naming the fields of the model that differ from the scene's.
    """
    if not isinstance(model, CableModel):
        raise TypeError(f"model: expected a CableModel, got {type(model).__name__}")
    expected = spec_from_scene(scene, model.spec.elements)
    differ = [
        f.name for f in fields(expected) if getattr(model.spec, f.name) != getattr(expected, f.name)
    ]
    if differ:
        raise ValueError(
            f"model: built for another scene ({', '.join(differ)} differ from this scene's); "
            "build it with CableModel.from_scene(scene[, elements]) or leave model out"
        )


def _line_simulation(scene, winch, model, initial_state, quiet, compiled):
    """A scene with ``[winch.line]``: :func:`cable_ocp.simulation.line_run.simulate_line`."""
    if model is not None or initial_state is not None:
        raise ValueError(
            "a scene with [winch.line] builds its models for every n itself: model and "
            "initial_state are not taken"
        )
    return simulate_line(scene, winch, quiet=quiet, compiled=compiled)
