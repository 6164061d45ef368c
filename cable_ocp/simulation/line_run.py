"""Simulation of a line paid out and hauled in by the drum: ``n`` changes along the run.

``simulate(scene)`` of a scene with ``[winch.line]`` comes here. The line out is
``L_out(t) = cable.length + r_D (phi(t) - phi(0))`` (the heave compensation included); its mesh
(:class:`~cable_ocp.scene.line_mesh.LineMesh`) gives ``n`` at every output time, and the run is
integrated as segments of constant ``n`` on the models of
:class:`~cable_ocp.model.line_models.LineModels` (one compiled library for every ``n``). At an
output time where ``n`` changes the state is mapped (:mod:`cable_ocp.model.line_state`: split
exactly, merge with the chord's offset) and the next segment starts from it, so changes fall on
output times: between two outputs the top element may leave its range by the line moved in one
output interval, at most half the shorter of ``Delta`` and ``l_min`` (:func:`check_line`,
before integrating).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cable_ocp.drive import winch as winch_angles
from cable_ocp.drive.bounds import BOUND_TOLERANCE
from cable_ocp.drive.drive import Drive, stage_times
from cable_ocp.drive.vessel import top_motion
from cable_ocp.model.cable import spec_from_scene
from cable_ocp.model.layout import INPUTS
from cable_ocp.model.line_models import line_models
from cable_ocp.model.line_state import merge, split
from cable_ocp.simulation.budget import check_simulation_memory
from cable_ocp.simulation.integrate import SimulationError, integrate, step_count, step_times
from cable_ocp.simulation.line_trajectory import LineTrajectory
from cable_ocp.simulation.outputs import output_trajectory, run_outputs
from cable_ocp.simulation.seabed import (
    check_on_grid,
    check_start,
    clearance_reference,
    rms_objective,
    seabed_height,
)
from cable_ocp.simulation.statics import starting_state
from cable_ocp.simulation.winch_input import winch_function


@dataclass(frozen=True)
class SegmentDrive:
    """A drive seen from a segment: time from ``start`` (s), the top element ``offset`` (m).

    ``base`` gives the drum's pay-out ``r_D (phi - phi(0))`` as its top length; the segment's
    top element is that plus ``offset = L_0 - (n - 1/2) Delta``.
    """

    base: Drive
    start: float
    offset: float

    def inputs(self, t: np.ndarray, left=None) -> np.ndarray:
        """Inputs ``u`` (15, len(t)) at the segment's times ``t`` (s)."""
        u = self.base.inputs(np.atleast_1d(np.asarray(t, dtype=float)) + self.start, left)
        u[INPUTS.top_length] += self.offset
        return u

    def stage_inputs(self, starts: np.ndarray, step: float) -> np.ndarray:
        """Inputs at the RK4 stages of the steps starting at ``starts`` (segment times, s)."""
        times, left = stage_times(starts, step)
        return self.inputs(times, left)


def pay_out_drive(scene, angle: winch_angles.WinchAngleFunction) -> Drive:
    """The scene's drive with the drum's pay-out ``r_D (phi - phi(0))`` (m) as its top length."""
    return Drive(
        top=top_motion(scene.top),
        angle=winch_angles.with_left(angle),
        end=scene.end,
        top_length=0.0,
        drum_radius=scene.winch.drum_radius,
        heave_compensation=scene.top.heave_compensated,
    )


def check_line(scene, drive: Drive, output_every: int) -> None:
    """Raise before integrating if the drum leaves its metres, or outputs are too far apart.

    The pay-out must stay in ``[-winch.line.haul_in_max, winch.line.pay_out_max]`` (within the
    angle tolerance of :mod:`cable_ocp.drive.bounds` as a length). Between two outputs, where
    ``n`` is held, the drum may pay out or haul in at most half the shorter of ``Delta`` and
    ``l_min`` from where it was at the output before: the top element then stays longer than
    ``l_min / 2`` (a short top element is a stiff pendulum that sets the RK4 limit; at
    ``Delta = 1.25 m``, 0.5 m/s and outputs 1 s apart one shrank to 0.11 m and blew up).
    """
    line, mesh = scene.winch.line, scene.winch.line.mesh
    tolerance = scene.winch.drum_radius * BOUND_TOLERANCE
    numerics = scene.numerics
    outputs = drive.inputs(
        np.arange(step_count(numerics.duration, numerics.step) // output_every + 1)
        * (output_every * numerics.step)
    )[INPUTS.top_length]
    allowed = min(mesh.element_length, mesh.top_length_min) / 2
    first, largest = 0, 0.0
    for times in step_times(numerics.duration, numerics.step):
        pay_out = drive.inputs(times)[INPUTS.top_length]
        for name, outside in (
            ("pay_out_max", pay_out > line.pay_out_max + tolerance),
            ("haul_in_max", -pay_out > line.haul_in_max + tolerance),
        ):
            if outside.any():
                k = int(np.argmax(outside))
                moved = (
                    f"pays out {pay_out[k]:.6g} m"
                    if pay_out[k] >= 0
                    else f"hauls in {-pay_out[k]:.6g} m"
                )
                raise ValueError(
                    f"the winch {moved} at t = {times[k]:.6g} s, beyond "
                    f"winch.line.{name} = {getattr(line, name)!r} m"
                )
        steps = np.arange(first, first + times.size)
        largest = max(largest, float(np.abs(pay_out - outputs[steps // output_every]).max()))
        first += times.size
    if largest > allowed:
        raise ValueError(
            f"numerics.output_every = {output_every}: the drum moves the line up to "
            f"{largest:.4g} m between two outputs ({output_every * numerics.step:g} s), more "
            f"than half the shorter of winch.line.element_length and the shortest top element "
            f"({allowed:.4g} m); elements change only at output times, so keep fewer steps per "
            "output"
        )


def simulate_line(scene, winch=None, quiet: bool = True, compiled: bool = True) -> LineTrajectory:
    """Simulate a scene with ``[winch.line]``: the line paid out and hauled in by elements.

    Parameters
    ----------
    scene : Scene
        With ``[winch.line]``.
    winch : None, array, callable or an ``optimize`` result
        As for :func:`cable_ocp.simulation.run.simulate`.
    quiet : bool
        No progress bar when true.
    compiled : bool
        The structured kernels compiled to C (one library for every ``n``) or interpreted.

    Returns
    -------
    LineTrajectory
        One :class:`Trajectory` per segment of constant ``n``.

    Raises
    ------
    ValueError
        Before integrating: the drum beyond ``winch.line``'s metres, outputs too far apart,
        outputs that cannot fit in memory (counted at the largest ``n`` of the run).
    SimulationError
        As :func:`~cable_ocp.simulation.integrate.integrate` raises it (bonds, blow-up).
    """
    numerics, mesh = scene.numerics, scene.winch.line.mesh
    drive = pay_out_drive(scene, winch_function(scene, winch))
    count = step_count(numerics.duration, numerics.step)
    if count % numerics.output_every:
        raise ValueError(
            f"numerics.output_every = {numerics.output_every} must divide the {count} steps"
        )
    check_line(scene, drive, numerics.output_every)
    interval = numerics.output_every * numerics.step
    times = np.arange(count // numerics.output_every + 1) * interval
    lines = scene.cable.length + drive.inputs(times)[INPUTS.top_length]
    counts = mesh.schedule(lines, mesh.starting_elements(scene.cable.length))
    # As if every output had the most elements.
    check_simulation_memory(scene, int(counts.max()), compiled=compiled)
    models = line_models(spec_from_scene(scene), mesh.element_length, compiled)
    changes = [0, *np.flatnonzero(np.diff(counts)) + 1, len(times) - 1]
    changes = sorted(set(changes))
    state, segments = None, []
    for first, last in zip(changes[:-1], changes[1:], strict=True):
        n = int(counts[first])
        model = models.model(n)
        local = SegmentDrive(drive, float(times[first]), scene.cable.length - mesh.below_top(n))
        if state is None:
            state = starting_state(model, local, compiled=True)
            check_start(scene.seabed, state[:3])
        try:
            run = integrate(
                model, state, local, (last - first) * interval, numerics.step,
                output_every=numerics.output_every, tolerance=numerics.constraint_tolerance,
                quiet=quiet, compiled=True, time_origin=local.start,
            )  # fmt: skip
        except SimulationError as error:
            where = f"in the segment of {n} elements from t = {local.start:g} s"
            raise SimulationError(f"{where}: {error}") from error
        outputs = run_outputs(model, run.states, run.inputs, True)
        segments.append((run.time + times[first], run, *outputs, model))
        state = _mapped(run.states[-1], run.inputs[-1], n, int(counts[last]), mesh)
    return _trajectory(scene, drive, segments)


def _mapped(state: np.ndarray, u: np.ndarray, elements: int, wanted: int, mesh) -> np.ndarray:
    """The state of ``wanted`` elements from that of ``elements`` at the same instant."""
    top_length = float(u[INPUTS.top_length])
    while elements < wanted:
        state = split(state, elements, mesh.element_length)
        elements, top_length = elements + 1, top_length - mesh.element_length
    while elements > wanted:
        state = merge(
            state, elements, mesh.element_length, top_length, u[INPUTS.top],
            u[INPUTS.top_velocity], float(u[INPUTS.top_length_rate]),
        )  # fmt: skip
        elements, top_length = elements - 1, top_length + mesh.element_length
    return state


def _trajectory(scene, drive: Drive, segments: list) -> LineTrajectory:
    """The segments as :class:`Trajectory` objects, ``e(t)`` and ``Omega`` of the whole run.

    ``e(t)`` takes its reference from the run's first end position, as a fixed-n run's does.
    """
    reference = clearance_reference(scene.seabed, segments[0][2][0, :, 0])
    errors = []
    for t, _, joints, *_ in segments:
        check_on_grid(scene.seabed, joints[:, :, 0], t)
        x, y, z = joints[:, :, 0].T
        errors.append(z - seabed_height(scene.seabed, x, y) - reference)
    whole_time = np.concatenate([t[:-1] for t, *_ in segments[:-1]] + [segments[-1][0]])
    whole_error = np.concatenate([e[:-1] for e in errors[:-1]] + [errors[-1]])
    omega = rms_objective(whole_time, whole_error)
    trajectories = [
        output_trajectory(
            scene, model, t, run.states, run.inputs, outputs, drive.winch_angle(t)[0], error, omega
        )
        for (t, run, *outputs, model), error in zip(segments, errors, strict=True)
    ]
    residual = max(run.bond_residual for _, run, *_ in segments)
    return LineTrajectory(trajectories, scene.winch.line.element_length, residual)
