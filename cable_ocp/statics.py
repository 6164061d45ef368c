"""Static equilibrium of the bonded chain: the hanging initial state of every dynamic scene.

The unknowns are the element angles only; positions follow by chaining the bonds down from the top
point, so the bonds hold exactly. The equations are ``q'' = 0`` for the angles at rest, from the
same right-hand side as the dynamics (so drag from a current is included), solved by Newton's method
from the string solution (the chain with its weight lumped per element) as a first guess.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from cable_ocp import structured
from cable_ocp.drive import Drive
from cable_ocp.kinematics import axis_direction
from cable_ocp.model import CableModel

RESIDUAL_TOLERANCE = 1e-10  # rad/s^2, largest angular acceleration left at the equilibrium
NEWTON_ITERATIONS = 50  # of the compiled Newton's method
DIFFERENCE_STEP = 1e-7  # rad, forward-difference step of its Jacobian


class EquilibriumError(RuntimeError):
    """Newton's method found no static equilibrium."""


def rest_inputs(drive: Drive) -> np.ndarray:
    """Inputs at t = 0 with the top and the winch at rest (15,)."""
    u = drive.inputs(np.zeros(1))[:, 0].copy()
    u[3:9] = 0.0
    u[10:12] = 0.0
    return u


def string_guess(model: CableModel, u: np.ndarray) -> np.ndarray:
    """Angles of the chain that carries its own weight and the end force as a string.

    Element ``i`` points along the force that holds everything below its middle.

    Returns
    -------
    array (n+1, 2), rad: psi and theta per element
    """
    spec = model.spec
    lengths = np.array(model.element_lengths(float(u[9])))
    below = np.cumsum(lengths) - lengths / 2
    weight = spec.element.submerged_weight_per_length
    payload = (spec.payload.mass - spec.water_density * spec.payload.volume) * spec.gravity
    pull = np.outer(weight * below + payload, [0.0, 0.0, 1.0]) - u[12:15]
    norms = np.linalg.norm(pull, axis=1)
    pull[norms < 1e-9] = [0.0, 0.0, 1.0]
    pull /= np.linalg.norm(pull, axis=1, keepdims=True)
    return np.column_stack([np.arctan2(pull[:, 2], pull[:, 0]), np.arcsin(pull[:, 1])])


def _state_from_angles(model: CableModel, angles: ca.SX, u: np.ndarray) -> ca.SX:
    """State at rest whose positions follow from the angles by chaining down from the top."""
    count, rotational = model.element_count, model.dofs - 3
    lengths = model.element_lengths(float(u[9]))
    point = ca.DM(u[0:3])
    q = [None] * count
    for i in reversed(range(count)):
        a = angles[i * rotational : (i + 1) * rotational]
        point = point - lengths[i] * axis_direction(a[0], a[1])
        q[i] = ca.vertcat(point, a)
    return ca.vertcat(*q, ca.SX.zeros(count * model.dofs))


def equilibrium(
    model: CableModel, drive: Drive, guess: np.ndarray | None = None, compiled: bool = False
) -> np.ndarray:
    """Static equilibrium of the model under the drive's inputs at t = 0.

    Parameters
    ----------
    model : CableModel
    drive : Drive
    guess : array (state_size,), optional
        A starting state; the string solution by default.
    compiled : bool
        For a 5-DOF model, Newton's method on the structured right-hand side compiled to C, with
        a finite-difference Jacobian (one mapped call): at n = 100, 0.05 s instead of the 5 s it
        takes to build the symbolic Jacobian. The equations and the tolerance are the same.

    Returns
    -------
    array (state_size,)
        The state at rest (all rates zero).

    Raises
    ------
    EquilibriumError
        If Newton's method does not converge.
    """
    u = rest_inputs(drive)
    count, dofs = model.element_count, model.dofs
    rotational = dofs - 3
    angles = ca.SX.sym("angles", count * rotational)
    x = _state_from_angles(model, angles, u)
    rotational_index = [i * dofs + 3 + k for i in range(count) for k in range(rotational)]
    unknowns = angles
    if model.spec.element.torsion:
        # A common spin of all elements stores no energy: hold the top element's twist at 0.
        unknowns = angles[: count * rotational - 1]
        x = ca.substitute(x, angles[-1], 0.0)
    if guess is None:
        start = np.zeros((count, rotational))
        start[:, :2] = string_guess(model, u)
        start = start.ravel()
    else:
        q_guess, _ = model.coordinates(np.asarray(guess, float))
        start = np.concatenate([qi[3:] for qi in q_guess])
    start = start[: unknowns.numel()]
    state_of = ca.Function("x", [unknowns], [x])
    if compiled and structured.supports(model):
        solution, left = _newton_compiled(model, state_of, u, rotational_index, start)
    else:
        solution, left = _newton_symbolic(model, state_of, u, rotational_index, unknowns, start)
    if not np.isfinite(left) or left > RESIDUAL_TOLERANCE:
        raise EquilibriumError(
            f"no static equilibrium found: Newton's method stopped with angular accelerations of "
            f"{left:.3g} rad/s^2 (tolerance {RESIDUAL_TOLERANCE:g}). Give a better guess state."
        )
    state = np.array(state_of(solution)).ravel()
    model.check_regular(state)
    return state


def _newton_symbolic(model, state_of, u, rotational_index, unknowns, start):
    """CasADi's Newton rootfinder on the SX equations; returns (solution, largest residual)."""
    acceleration = model.rhs(state_of(unknowns), u)[model.state_size // 2 :]
    residual = acceleration[rotational_index][: unknowns.numel()]
    solver = ca.rootfinder(
        "equilibrium",
        "newton",
        ca.Function("g", [unknowns], [residual]),
        {"abstol": RESIDUAL_TOLERANCE, "max_iter": 100, "error_on_fail": False},
    )
    solution = np.array(solver(start)).ravel()
    left = np.max(np.abs(np.array(ca.Function("r", [unknowns], [residual])(solution))))
    return solution, float(left)


def _newton_compiled(model, state_of, u, rotational_index, start):
    """Newton's method with a forward-difference Jacobian on the compiled structured rhs."""
    rhs = structured.compiled_structured(model, "rhs")
    size = start.size
    half = model.state_size // 2
    index = np.array(rotational_index[:size]) + half
    batch = rhs.map(size + 1)
    states = state_of.map(size + 1)
    solution = start.copy()
    left = np.inf
    for _ in range(NEWTON_ITERATIONS):
        probes = solution[:, None] + np.hstack(
            [np.zeros((size, 1)), DIFFERENCE_STEP * np.eye(size)]
        )
        residuals = np.array(batch(states(probes), u))[index]
        residual = residuals[:, 0]
        left = float(np.max(np.abs(residual)))
        if not np.isfinite(left) or left <= RESIDUAL_TOLERANCE:
            break
        jacobian = (residuals[:, 1:] - residual[:, None]) / DIFFERENCE_STEP
        solution = solution - np.linalg.solve(jacobian, residual)
    return solution, left
