"""The front door for simulation: ``simulate(scene, winch=...)`` returns a :class:`Trajectory`."""

from __future__ import annotations

from collections.abc import Callable, Iterator

import casadi as ca
import numpy as np

from cable_ocp.drive import winch as winch_angles
from cable_ocp.drive.bounds import BOUND_TOLERANCE
from cable_ocp.drive.drive import Drive
from cable_ocp.model import structured
from cable_ocp.model.cable import CableModel
from cable_ocp.model.layout import INPUTS
from cable_ocp.scene.given import scene_given
from cable_ocp.simulation.budget import check_simulation_memory
from cable_ocp.simulation.integrate import evaluate_into, integrate
from cable_ocp.simulation.landing_reference import reference_error
from cable_ocp.simulation.seabed import (
    check_on_grid,
    check_start,
    clearance_error,
    rms_objective,
)
from cable_ocp.simulation.slack import signed_tensions
from cable_ocp.simulation.statics import starting_state
from cable_ocp.simulation.trajectory import Trajectory

WinchSpec = None | np.ndarray | Callable
# States per call of the mapped outputs: CasADi's map takes superlinear time in its count (at
# n = 100, 0.4 s to map over 4001 states, 0.02 s over 500), the call the same time per state.
OUTPUT_BLOCK = 500
# Times per block of the top-length check: the inputs of a block are 120 B a time, so a run of
# 3.6e7 steps is checked in 4 MB blocks, not one 4.3 GB array.
TIME_BLOCK = 32_768
# Largest share of the line out that the graded mesh's top element may carry (check_top_length).
TOP_SHARE = 1 / 3


def winch_function(scene, winch: WinchSpec) -> winch_angles.WinchAngleFunction:
    """Turn a winch specification into an angle history.

    Parameters
    ----------
    winch : None, array, callable or a result
        None: locked. An array of ``scene.winch.knots`` values: the cubic spline through them
        (rad, ``phi(0) = 0``). A callable ``t -> (phi, phi', phi'')``: used as it is. A result
        of ``optimize`` or ``mpc`` (anything with a ``winch_profile(scene)`` method), or one
        retimed (``result.retimed("hold")``): its winch on this scene, the heave feedforward or
        feedback included where it rode on one (a replay).
    """
    if winch is None:
        return winch_angles.locked
    if hasattr(winch, "winch_profile"):
        return winch.winch_profile(scene)
    if callable(winch):
        return winch
    try:
        values = np.asarray(winch, dtype=float).ravel()
    except (TypeError, ValueError):
        raise ValueError(f"winch: expected {scene.winch.knots} knot angles in rad") from None
    if values.size != scene.winch.knots:
        raise ValueError(
            f"winch: {values.size} knot values given; the scene has winch.knots = "
            f"{scene.winch.knots}"
        )
    if not np.isfinite(values).all():
        k = int(np.argmin(np.isfinite(values)))
        raise ValueError(f"winch: knot value {k + 1} is {values[k]}: must be finite (rad)")
    return winch_angles.spline_angle(scene.numerics.duration, values)


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
        _check_rod(scene, drive, length, times, tolerance)
        high = np.inf
    outside = (length < low - tolerance) | (length > high + tolerance)
    if outside.any():
        k = int(np.argmax(outside))
        raise ValueError(
            f"the winch sets the top-element length to {length[k]:.4g} m at t = {times[k]:.6g} s, "
            f"outside [winch.top_length_min, winch.top_length_max] = [{low}, {high}] m by more "
            f"than the tolerance {tolerance:.3g} m"
        )


def _check_rod(scene, drive: Drive, length, times, tolerance) -> None:
    """Refuse a graded top element paid out to more than :data:`TOP_SHARE` of the line out.

    Without ``winch.top_length_max`` the graded mesh's top element grows by all the drum pays
    out: a rigid rod, not a rope, once it carries a large share of the line (measured: 300 m of
    drum range on ``paper_hill`` gave a 210 m rod, silently).
    """
    line = scene.cable.length + length - drive.top_length
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


def step_times(duration: float, step: float) -> Iterator[np.ndarray]:
    """The times of a run's RK4 grid, ``0, h, ..., T`` (s), in blocks of :data:`TIME_BLOCK`.

    Together they are ``np.linspace(0, duration, count + 1)``, without the array of all of them.
    """
    count = int(round(duration / step))
    spacing = duration / count
    for first in range(0, count + 1, TIME_BLOCK):
        stop = min(first + TIME_BLOCK, count + 1)
        times = np.arange(first, stop) * spacing
        if stop == count + 1:
            times[-1] = duration  # as linspace ends
        yield times


def checked_state(state, size: int) -> np.ndarray:
    """``state`` as a float vector of ``size`` finite values, or ValueError naming what is wrong."""
    try:
        values = np.asarray(state, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(
            f"initial_state: expected {size} numbers, got {type(state).__name__}"
        ) from None
    if values.shape != (size,):
        raise ValueError(
            f"initial_state: expected shape ({size},) (the model's state_size), got {values.shape}"
        )
    if not np.isfinite(values).all():
        k = int(np.argmin(np.isfinite(values)))
        raise ValueError(f"initial_state[{k}] = {values[k]}: must be finite")
    return values


def joints_and_tensions(
    model: CableModel, states: np.ndarray, inputs: np.ndarray, compiled: bool = False
) -> tuple[np.ndarray, np.ndarray]:
    """Joint positions (k, 3, n+2; m) and bond tensions ``|lambda_j|`` (k, n+1; N) of k states.

    The first two of :func:`run_outputs`.
    """
    joints, tensions, _ = run_outputs(model, states, inputs, compiled)
    return joints, tensions


def run_outputs(
    model: CableModel, states: np.ndarray, inputs: np.ndarray, compiled: bool = False
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Joint positions (k, 3, n+2; m), bond tensions and signed tensions (k, n+1; N).

    The tensions are ``|lambda_j|``, the signed ones along the element axes
    (:func:`~cable_ocp.simulation.slack.signed_tensions`).

    One evaluation of the model's joints and bond forces, :data:`OUTPUT_BLOCK` states at a
    time. Compiled, a 5-DOF model evaluates them with the structured loops compiled to C
    (cached): at n = 100 the interpreted outputs cost twice the whole compiled integration.
    The norms are those of the model's ``tensions`` output, to the last bit.
    """
    count, joint_count, bonds = len(states), model.element_count + 1, model.element_count
    structured_outputs = compiled and structured.supports(model)
    # Column-major CasADi results, written as their C-ordered transposes.
    joints = np.empty((count * joint_count, 3))
    forces = np.empty((count * bonds, 3))
    tensions = np.empty((count, bonds))
    for first in range(0, count, OUTPUT_BLOCK):
        rows = slice(first, min(first + OUTPUT_BLOCK, count))
        results = [
            joints[rows.start * joint_count : rows.stop * joint_count],
            forces[rows.start * bonds : rows.stop * bonds],
        ]
        if not structured_outputs:
            results.append(tensions[rows])
        evaluate_into(
            _outputs_function(model, rows.stop - rows.start, structured_outputs),
            [states[rows], inputs[rows]],
            results,
        )
    joints = joints.reshape(count, joint_count, 3).transpose(0, 2, 1)
    forces = forces.reshape(count, bonds, 3).transpose(0, 2, 1)
    if structured_outputs:  # the structured norm: sqrt of the squares summed in order
        tensions = np.sqrt(np.sum(forces**2, axis=1))
    return joints, tensions, signed_tensions(joints, forces)


def _outputs_function(model: CableModel, count: int, structured_outputs: bool) -> ca.Function:
    """``count`` states and inputs -> joints and bond forces (and, interpreted, tensions)."""
    if structured_outputs:
        return structured.compiled_structured(model, "joints_and_forces", count)
    return model.memo(("joints_forces_tensions", count), lambda: _model_outputs(model, count))


def _model_outputs(model: CableModel, count: int):
    """``count`` states and inputs -> joints, bond forces and tensions, the model's outputs."""
    outputs = model.outputs
    x, u = outputs.mx_in("x"), outputs.mx_in("u")
    results = outputs(x=x, u=u)
    names = ["joints", "bond_forces", "tensions"]
    single = ca.Function(
        "joints_forces_tensions", [x, u], [results[name] for name in names], ["x", "u"], names
    )
    return single.map(count)


def simulate(
    scene,
    winch: WinchSpec = None,
    model: CableModel | None = None,
    initial_state: np.ndarray | None = None,
    quiet: bool = True,
    compiled: bool = False,
) -> Trajectory:
    """Simulate a scene by RK4 from its static equilibrium.

    See :func:`checked_simulation`, which also returns the run's largest bond residual. The
    run's physics (a rope that pushes, an end under an absolute seabed, a drum beyond
    ``[winch.angle_min, winch.angle_max]``) is checked after it:
    ``trajectory.success``, ``status`` and ``summary()`` say where and when
    (:mod:`cable_ocp.simulation.slack`); a run that fails it is returned, not raised.
    """
    return checked_simulation(scene, winch, model, initial_state, quiet, compiled)[0]


def checked_simulation(
    scene,
    winch: WinchSpec = None,
    model: CableModel | None = None,
    initial_state: np.ndarray | None = None,
    quiet: bool = True,
    compiled: bool = False,
) -> tuple[Trajectory, float]:
    """Simulate a scene by RK4 from its static equilibrium; with the largest bond residual (m).

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
    trajectory : Trajectory
    bond_residual : float, m
        Largest bond residual of the run's states after the first, as the integration checked
        them (the health check of the run).

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
    check_simulation_memory(scene, model.spec.elements if model is not None else None)
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
    return trajectory, run.bond_residual


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
    joints, tensions, signed = run_outputs(model, states, inputs, compiled)
    check_on_grid(scene.seabed, joints[:, :, 0], time)
    error = clearance_error(scene.seabed, joints[:, :, 0])
    error = error - reference_error(scene, time, error[0])
    return Trajectory(
        time=time,
        states=states,
        inputs=inputs,
        joints=joints,
        tensions=tensions,
        winch_angle=winch_angle,
        clearance_error=error,
        omega=rms_objective(time, error) if time.size > 1 else float("nan"),
        scene_name=scene.name,
        scene_record=scene.to_dict(),
        state_names=model.state_names,
        signed_tensions=signed,
    )


def _line_simulation(scene, winch, model, initial_state, quiet, compiled):
    """A scene with ``[winch.line]``: :func:`cable_ocp.simulation.line_run.simulate_line`."""
    from cable_ocp.simulation.line_run import simulate_line  # it imports this module

    if model is not None or initial_state is not None:
        raise ValueError(
            "a scene with [winch.line] builds its models for every n itself: model and "
            "initial_state are not taken"
        )
    trajectory = simulate_line(scene, winch, quiet=quiet, compiled=compiled)
    return trajectory, trajectory.bond_residual
