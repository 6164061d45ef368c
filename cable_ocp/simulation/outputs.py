"""A run's outputs from its states: joint positions, bond tensions and their signs.

One evaluation of the model's ``outputs`` (or, compiled, the structured loops) over many
states, :data:`OUTPUT_BLOCK` at a time, and the :class:`Trajectory` made of them
(:func:`output_trajectory`); shared by the fixed-n runs (:mod:`.run`) and the line runs
(:mod:`.line_run`).
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from cable_ocp.model import structured
from cable_ocp.model.cable import CableModel
from cable_ocp.simulation.integrate import evaluate_into
from cable_ocp.simulation.slack import signed_tensions
from cable_ocp.simulation.trajectory import Trajectory

# States per call of the mapped outputs: CasADi's map takes superlinear time in its count (at
# n = 100, 0.4 s to map over 4001 states, 0.02 s over 500), the call the same time per state.
OUTPUT_BLOCK = 500


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


def output_trajectory(
    scene,
    model: CableModel,
    time: np.ndarray,
    states: np.ndarray,
    inputs: np.ndarray,
    outputs: tuple[np.ndarray, np.ndarray, np.ndarray],
    winch_angle: np.ndarray,
    clearance_error: np.ndarray,
    omega: float,
) -> Trajectory:
    """The :class:`Trajectory` of a run of ``model`` on ``scene``, from its outputs.

    Parameters
    ----------
    scene : Scene
    model : CableModel
    time : array (k,), s
    states : array (k, state_size)
    inputs : array (k, 15)
    outputs : tuple of arrays
        Joints (k, 3, n+2; m), tensions and signed tensions (k, n+1; N): :func:`run_outputs`.
    winch_angle : array (k,), rad
        The drum angle that drove the run.
    clearance_error : array (k,), m
        ``e(t)`` of eq. 39.
    omega : float, m
        ``Omega`` of eq. 39.
    """
    joints, tensions, signed = outputs
    return Trajectory(
        time=time,
        states=states,
        inputs=inputs,
        joints=joints,
        tensions=tensions,
        winch_angle=winch_angle,
        clearance_error=clearance_error,
        omega=omega,
        scene_name=scene.name,
        scene_record=scene.to_dict(),
        state_names=model.state_names,
        signed_tensions=signed,
    )
