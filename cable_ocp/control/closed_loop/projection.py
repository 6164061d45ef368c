"""The controller's state estimate: the plant's measured state projected onto the reduced model.

The reduced model (fewer, longer elements) cannot take the plant's state as it is. Its joints
below the top are placed on the plant's cable at the same arc length from the end ``E`` (a point
between two plant joints lies on the straight plant element joining them, so linear interpolation
along the polyline is exact), and each reduced element points along the chord to the next one; the
top element points at the top point. The positions are then chained down from the top with the
reduced model's own element lengths, so its bonds hold exactly, and the end of the chain differs
from the measured end only by what the chords cut off the curved cable (the controller corrects
its predictions by that offset, :func:`project_state`).

Velocities likewise: the plant's joint velocities are interpolated at the same arc lengths (exact
on a rigid element), each reduced element turns at the rate of its chord's normal velocity, and
the joint velocities are chained down from the top with the winch's pay-out rate, so the bonds
hold at velocity level too.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cable_ocp.model.cable import CableModel

# Relative excess of the reduced model's top joint over the plant's that is rounding, not a
# reduced model reaching higher (30.000000000000007 m against 30.000000000000004 m).
ARC_TOLERANCE = 1e-9


@dataclass(frozen=True)
class ProjectedState:
    """A reduced-model state made from a plant state.

    Attributes
    ----------
    state : array (reduced state_size,)
    end_offset : array (3,), m
        Measured end position minus the end of the reduced chain.
    """

    state: np.ndarray
    end_offset: np.ndarray


def axis(psi: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """Element direction ``e(psi, theta)`` of CONVENTIONS.md §3 (3, ...)."""
    return np.array([np.cos(theta) * np.cos(psi), np.sin(theta), np.cos(theta) * np.sin(psi)])


def axis_derivatives(psi, theta) -> tuple[np.ndarray, np.ndarray]:
    """``de/dpsi`` and ``de/dtheta`` of :func:`axis` (each (3, ...))."""
    zero = np.zeros_like(np.asarray(psi, float))
    d_psi = np.array([-np.cos(theta) * np.sin(psi), zero, np.cos(theta) * np.cos(psi)])
    d_theta = np.array([-np.sin(theta) * np.cos(psi), np.cos(theta), -np.sin(theta) * np.sin(psi)])
    return d_psi, d_theta


def chain_state(
    model: CableModel,
    top: np.ndarray,
    top_velocity: np.ndarray,
    top_length: float,
    top_length_rate: float,
    directions: np.ndarray,
    direction_rates: np.ndarray,
    strain: tuple[float, float] = (0.0, 0.0),
) -> np.ndarray:
    """A state whose bonds hold exactly, chained down from the top point.

    Parameters
    ----------
    model : CableModel
        A 5-DOF model.
    top, top_velocity : array (3,), m, m/s
        The top point ``A_{n+1}`` and its velocity.
    top_length, top_length_rate : float, m, m/s
        ``l_n`` and its rate (the winch).
    directions : array (n+1, 3)
        Direction of each element (normalised here).
    direction_rates : array (n+1, 3), 1/s
        Rate of each direction; the part along the direction is dropped.
    strain : (float, float)
        An elastic rope's axial strain and its rate (1/s), which stretch every element
        (:mod:`cable_ocp.model.axial`); ignored by a rigid model.

    Returns
    -------
    array (state_size,)
    """
    if model.spec.element.torsion:
        raise ValueError("the state projection supports 5-DOF models only (model.torsion = false)")
    count = model.element_count
    strain, strain_rate = strain if model.axial else (0.0, 0.0)
    rest = np.array([float(v) for v in model.element_lengths(top_length)])
    lengths = (1 + strain) * rest
    rates = strain_rate * rest
    rates[-1] += (1 + strain) * top_length_rate
    q = np.zeros((count, 5))
    qd = np.zeros((count, 5))
    point = np.asarray(top, float).copy()
    velocity = np.asarray(top_velocity, float).copy()
    for i in reversed(range(count)):
        e = directions[i] / np.linalg.norm(directions[i])
        psi, theta = np.arctan2(e[2], e[0]), np.arcsin(np.clip(e[1], -1.0, 1.0))
        d_psi, d_theta = axis_derivatives(psi, theta)
        e_rate = direction_rates[i] - np.dot(direction_rates[i], e) * e
        psi_rate = np.dot(e_rate, d_psi) / np.cos(theta) ** 2
        theta_rate = np.dot(e_rate, d_theta)
        e_rate = psi_rate * d_psi + theta_rate * d_theta
        point = point - lengths[i] * e
        velocity = velocity - rates[i] * e - lengths[i] * e_rate
        q[i] = [*point, psi, theta]
        qd[i] = [*velocity, psi_rate, theta_rate]
    axial = [strain] * model.axial, [strain_rate] * model.axial
    return np.concatenate([q.ravel(), axial[0], qd.ravel(), axial[1]])


def strain_of(model: CableModel, x: np.ndarray) -> tuple[float, float]:
    """An elastic state's axial strain and its rate (1/s); zeros for a rigid model."""
    if not model.axial:
        return 0.0, 0.0
    strain, rate = model.strain(np.asarray(x, float))
    return float(strain), float(rate)


def joint_arcs(model: CableModel, top_length: float) -> np.ndarray:
    """Rest arc length (m) from the end ``E`` to each joint ``A_0 .. A_{n+1}``.

    An elastic rope's strain is uniform: each arc stretches by the same factor, so rest arcs
    interpolate the stretched line as they do the rigid one.
    """
    lengths = [float(v) for v in model.element_lengths(top_length)]
    return np.concatenate([[0.0], np.cumsum(lengths)])


def plant_joints(model: CableModel, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Joints ``A_0 .. A_n`` (n+1, 3) and their velocities of a 5-DOF state (the top excluded)."""
    q, qd = model.coordinates(np.asarray(x, float))
    return np.array([qi[:3] for qi in q]), np.array([qdi[:3] for qdi in qd])


def project_state(
    plant: CableModel,
    x: np.ndarray,
    plant_top_length: float,
    reduced: CableModel,
    top: np.ndarray,
    top_velocity: np.ndarray,
    top_length: float,
    top_length_rate: float,
) -> ProjectedState:
    """Project a plant state onto the reduced model (see the module docstring).

    Parameters
    ----------
    plant : CableModel
        The plant's (full) model.
    x : array (plant state_size,)
        The measured plant state.
    plant_top_length : float, m
        The plant's top-element length at the moment of the measurement.
    reduced : CableModel
        The controller's model.
    top, top_velocity : array (3,), m, m/s
        The top point (and velocity) the reduced state hangs from.
    top_length, top_length_rate : float, m, m/s
        The reduced model's top-element length and its rate.
    """
    joints, velocities = plant_joints(plant, x)
    arcs = joint_arcs(plant, plant_top_length)[:-1]
    wanted = joint_arcs(reduced, top_length)[:-1]
    if wanted[-1] > arcs[-1] + ARC_TOLERANCE * max(arcs[-1], 1.0):  # not a rounding's excess
        raise ValueError(
            f"the reduced model's top joint lies {wanted[-1]:.4g} m from the end, beyond the "
            f"plant's top joint ({arcs[-1]:.4g} m): use fewer reduced elements"
        )
    points = np.column_stack([np.interp(wanted, arcs, joints[:, k]) for k in range(3)])
    rates = np.column_stack([np.interp(wanted, arcs, velocities[:, k]) for k in range(3)])
    upper = np.vstack([points[1:], np.asarray(top, float)])
    upper_rates = np.vstack([rates[1:], np.asarray(top_velocity, float)])
    chords = upper - points
    chord_lengths = np.linalg.norm(chords, axis=1, keepdims=True)
    state = chain_state(
        reduced,
        top,
        top_velocity,
        top_length,
        top_length_rate,
        chords,
        (upper_rates - rates) / chord_lengths,
        strain_of(plant, x),
    )
    return ProjectedState(state=state, end_offset=joints[0] - state[:3])


def onto_bonds(
    model: CableModel,
    x: np.ndarray,
    top: np.ndarray,
    top_velocity: np.ndarray,
    top_length: float,
    top_length_rate: float,
) -> np.ndarray:
    """A 5-DOF state moved onto its bonds: each element keeps its direction and turning rate.

    The joints and their velocities are chained down again from the top point
    (:func:`chain_state`), so the bond residual becomes zero at position and velocity level;
    each joint moves by at most the sum of the residuals above it.

    Parameters
    ----------
    model : CableModel
    x : array (state_size,)
    top, top_velocity : array (3,), m, m/s
        The top point ``A_{n+1}`` and its velocity.
    top_length, top_length_rate : float, m, m/s
        ``l_n`` and its rate.
    """
    q, qd = model.coordinates(np.asarray(x, float))
    psi, theta = np.array([qi[3] for qi in q]), np.array([qi[4] for qi in q])
    psi_rate, theta_rate = np.array([v[3] for v in qd]), np.array([v[4] for v in qd])
    d_psi, d_theta = axis_derivatives(psi, theta)
    rates = (psi_rate * d_psi + theta_rate * d_theta).T
    return chain_state(
        model,
        top,
        top_velocity,
        top_length,
        top_length_rate,
        axis(psi, theta).T,
        rates,
        strain_of(model, x),
    )
