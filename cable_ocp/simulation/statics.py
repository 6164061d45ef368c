"""Static equilibrium of the bonded chain: the hanging initial state of every dynamic scene.

The unknowns are the element angles only; positions follow by chaining the bonds down from the top
point, so the bonds hold exactly. The equations are ``q'' = 0`` for the angles at rest, from the
same right-hand side as the dynamics (so drag from a current is included), solved by Newton's method
from the string solution (the chain with its weight, the end force and the current's drag lumped per
element) as a first guess. The equations also hold for a chain standing up in compression (in a
strong current the straight cable mirrored through the top balances as well), so every solution is
checked to be physical: all bonds pull, and a cable heavier than water hangs with its end below the
top.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from cable_ocp.drive.drive import Drive
from cable_ocp.model import structured
from cable_ocp.model.cable import CableModel, Payload
from cable_ocp.model.current import current_values, has_current
from cable_ocp.model.hydro import HydroCoefficients
from cable_ocp.model.kinematics import axis_direction
from cable_ocp.model.layout import INPUTS
from cable_ocp.simulation.seabed import check_start
from cable_ocp.simulation.slack import signed_tensions

RESIDUAL_TOLERANCE = 1e-10  # rad/s^2, largest angular acceleration left at the equilibrium
NEWTON_ITERATIONS = 50  # of the compiled Newton's method
DIFFERENCE_STEP = 1e-7  # rad, forward-difference step of its Jacobian
LINE_SEARCH_HALVINGS = 20  # of its step, at most
STARTING_STATES_KEPT = 8  # starting states kept per model, the oldest dropped first
# A bond pushes if its tension is below -1e-6 of the larger of the largest bond force and the weight
# in air (the equilibria's tensions are exact to ~1e-10 of that, so noise never trips it).
COMPRESSION_TOLERANCE = 1e-6


class EquilibriumError(RuntimeError):
    """Newton's method found no static equilibrium, or one that no cable can hang in."""


def rest_inputs(drive: Drive) -> np.ndarray:
    """Inputs at t = 0 with the top and the winch at rest (15,)."""
    u = drive.inputs(np.zeros(1))[:, 0].copy()
    u[INPUTS.top_velocity] = 0.0
    u[INPUTS.top_acceleration] = 0.0
    u[INPUTS.top_length_rate] = 0.0
    u[INPUTS.top_length_acceleration] = 0.0
    return u


def string_guess(model: CableModel, u: np.ndarray) -> np.ndarray:
    """Angles of the chain that carries its weight, end force and the current's drag as a string.

    Element ``i`` points along the force that holds everything below its middle: the pull ``P``
    at its lower joint plus half its own load. That is the moment balance of a straight element
    about its upper joint, so without bending stiffness this is the equilibrium itself. In a
    current the element's own normal drag ``1/2 rho_w d C_dn |v_n| v_n`` (``v_n`` the current's
    part across the element) depends on its direction ``e``; the balance
    ``e || P + l/2 (w e_z - f(e))`` puts ``e`` along ``R - k v`` (``R`` all loads but the
    element's own drag, ``v`` the current) with ``k >= 0`` the smallest root of
    ``k |R - k v| = l/2 * 1/2 rho_w d C_dn |v x R|``, found per element from the free end up.
    Axial drag acts along ``e`` and only adds to the pull on the elements above.

    Returns
    -------
    array (n+1, 2), rad: psi and theta per element
    """
    spec = model.spec
    lengths = np.array(model.element_lengths(float(u[INPUTS.top_length])))
    below = np.cumsum(lengths) - lengths / 2
    weight = spec.element.submerged_weight_per_length
    pull = np.outer(weight * below + spec.payload_weight, [0.0, 0.0, 1.0]) - u[INPUTS.end_force]
    hydro = spec.element.hydro
    if hydro is not None and hydro.has_drag and has_current(hydro):
        # The current at each element's middle and at E as if the line hung straight down.
        heights = u[INPUTS.top][2] - (lengths.sum() - np.append(below, 0.0))
        currents = current_values(hydro, heights)
        pull = _trailing_pulls(pull, lengths, hydro, spec.payload, currents[:-1], currents[-1])
    norms = np.linalg.norm(pull, axis=1)
    pull[norms < 1e-9] = [0.0, 0.0, 1.0]
    pull /= np.linalg.norm(pull, axis=1, keepdims=True)
    return np.column_stack([np.arctan2(pull[:, 2], pull[:, 0]), np.arcsin(pull[:, 1])])


def _trailing_pulls(
    still: np.ndarray,
    lengths: np.ndarray,
    hydro: HydroCoefficients,
    payload: Payload,
    currents: np.ndarray,
    end_current: np.ndarray,
) -> np.ndarray:
    """Directions (n+1, 3) that hold each element in the current, from the still-water pulls.

    ``still[i]`` holds the weight below the middle of element ``i`` and the end force; the drag of
    the payload and of the elements below ``i`` is subtracted, then element ``i`` turns by its own
    normal drag (see :func:`string_guess`). ``currents[i]`` (m/s) is the current at element ``i``,
    ``end_current`` the current at E (the payload's).
    """
    half_rho_d = 0.5 * hydro.water_density * hydro.diameter
    payload_drag = 0.5 * hydro.water_density * payload.drag_coefficient * payload.drag_area
    drag_below = payload_drag * np.linalg.norm(end_current) * end_current
    pulls = np.empty_like(still)
    for i, (length, current) in enumerate(zip(lengths, currents, strict=True)):
        loads = still[i] - drag_below
        turn = (
            length / 2 * half_rho_d * hydro.drag_normal * np.linalg.norm(np.cross(current, loads))
        )
        k = _smallest_root(current, loads, turn)
        pulls[i] = loads - k * current
        axis = pulls[i] / np.linalg.norm(pulls[i])
        axial = (current @ axis) * axis
        normal = current - axial
        drag_below = drag_below + length * half_rho_d * (
            hydro.drag_normal * np.linalg.norm(normal) * normal
            + np.pi * hydro.drag_axial * np.linalg.norm(axial) * axial
        )
    return pulls


def _smallest_root(current: np.ndarray, loads: np.ndarray, turn: float) -> float:
    """Smallest ``k >= 0`` with ``k |loads - k current| = turn`` (a quartic in ``k``)."""
    if turn == 0.0:
        return 0.0
    roots = np.roots([current @ current, -2 * (current @ loads), loads @ loads, 0.0, -(turn**2)])
    real = roots.real[(np.abs(roots.imag) <= 1e-6 * np.abs(roots)) & (roots.real >= 0)]
    return float(real.min())


def _state_from_angles(model: CableModel, angles: ca.SX, u: np.ndarray) -> ca.SX:
    """State at rest whose positions follow from the angles by chaining down from the top.

    An elastic model's strain is the last unknown after the angles: every length stretches by it.
    """
    count, rotational = model.element_count, model.dofs - 3
    lengths = model.element_lengths(float(u[INPUTS.top_length]))
    strain = angles[count * rotational :]
    stretch = 1 + strain if model.axial else 1
    point = ca.DM(u[INPUTS.top])
    q = [None] * count
    for i in reversed(range(count)):
        a = angles[i * rotational : (i + 1) * rotational]
        point = point - stretch * lengths[i] * axis_direction(a[0], a[1])
        q[i] = ca.vertcat(point, a)
    return ca.vertcat(*q, strain, ca.SX.zeros(model.state_size // 2))


@dataclass(frozen=True, eq=False)
class Equilibrium:
    """A static equilibrium: the state at rest and what it looks like.

    Attributes
    ----------
    state : array (state_size,)
        Coordinates of the elements, all rates zero: where a run starts.
    inputs : array (15,)
        The inputs it holds under: the top and the winch at rest (:mod:`cable_ocp.model.layout`).
    joints : array (3, n+2), m
        ``A_0`` (the free end) .. ``A_{n+1}`` (the top).
    tensions : array (n+1,), N
        Signed bond tensions, positive pulling (:func:`bond_tensions`).
    residual : float, rad/s^2
        Largest angular acceleration left by Newton's method.
    """

    state: np.ndarray
    inputs: np.ndarray
    joints: np.ndarray
    tensions: np.ndarray
    residual: float

    @property
    def end(self) -> np.ndarray:
        """Position of the free end ``E = A_0`` (3,), m."""
        return self.joints[:, 0]


def equilibrium(
    model: CableModel,
    drive: Drive,
    guess: np.ndarray | Equilibrium | None = None,
    compiled: bool = False,
) -> Equilibrium:
    """Static equilibrium of the model under the drive's inputs at t = 0.

    Parameters
    ----------
    model : CableModel
    drive : Drive
    guess : array (state_size,) or Equilibrium, optional
        A starting state (e.g. the equilibrium of the scene in a weaker current); the string
        solution with the current's drag by default.
    compiled : bool
        For a 5-DOF model, Newton's method on the structured right-hand side compiled to C, with
        a finite-difference Jacobian (one mapped call): at n = 100, 0.05 s instead of the 5 s it
        takes to build the symbolic Jacobian. The equations and the tolerance are the same.

    Returns
    -------
    Equilibrium
        The state at rest (``.state``, all rates zero) with its joints and bond tensions.

    Raises
    ------
    EquilibriumError
        If Newton's method does not converge, or converges to an equilibrium that is not physical
        (:func:`check_physical`: a bond in compression, or a cable heavier than water whose end
        stands above the top).
    """
    u = rest_inputs(drive)
    count, dofs = model.element_count, model.dofs
    rotational = dofs - 3
    angles = ca.SX.sym("angles", count * rotational + model.axial)
    x = _state_from_angles(model, angles, u)
    rotational_index = [i * dofs + 3 + k for i in range(count) for k in range(rotational)]
    rotational_index += [model.state_size // 2 - 1] * model.axial  # the strain's acceleration
    unknowns = angles
    if model.spec.element.torsion:
        # A common spin of all elements stores no energy: hold the top element's twist at 0.
        unknowns = angles[: count * rotational - 1]
        x = ca.substitute(x, angles[-1], 0.0)
    if isinstance(guess, Equilibrium):
        guess = guess.state
    if guess is None:
        start = np.zeros((count, rotational))
        start[:, :2] = string_guess(model, u)
        start = np.concatenate([start.ravel(), np.zeros(model.axial)])
    else:
        q_guess, _ = model.coordinates(np.asarray(guess, float))
        half = model.state_size // 2
        strain = np.asarray(guess, float)[half - model.axial : half]
        start = np.concatenate([qi[3:] for qi in q_guess] + [strain])
    start = start[: unknowns.numel()]
    state_of = ca.Function("x", [unknowns], [x])
    if compiled and structured.supports(model):
        solution, left = _newton_compiled(model, state_of, u, rotational_index, start)
        if model.axial and not left <= RESIDUAL_TOLERANCE:
            # The strain's finite difference can stall the compiled Newton (a 66 mm synthetic
            # rope of 547 m in a current stopped at 0.03 rad/s^2): start again on the exact one.
            solution, left = _newton_symbolic(model, state_of, u, rotational_index, unknowns, start)
    else:
        solution, left = _newton_symbolic(model, state_of, u, rotational_index, unknowns, start)
    if not np.isfinite(left) or left > RESIDUAL_TOLERANCE:
        raise EquilibriumError(
            f"no static equilibrium found: Newton's method stopped with angular accelerations of "
            f"{left:.3g} rad/s^2 (tolerance {RESIDUAL_TOLERANCE:g}). Give a better guess state."
        )
    state = np.array(state_of(solution)).ravel()
    model.check_regular(state)
    outputs = _joints_and_forces(model, state, u, compiled)
    tensions = signed_tensions(outputs["joints"], outputs["bond_forces"])
    found = Equilibrium(state, u, outputs["joints"], tensions, float(left))
    check_physical(model, found)
    return found


def _joints_and_forces(model: CableModel, state, u, compiled: bool) -> dict[str, np.ndarray]:
    """Joints (3, n+2; m) and bond forces (3, n+1; N) at one state.

    Compiled, a 5-DOF model takes them from the structured loops that it integrates with, so that
    the flat outputs are not built for one evaluation (1 s at n = 100); equal to rounding.
    """
    if not (compiled and structured.supports(model)):
        return model.output_values(state, u)
    joints_and_forces = structured.compiled_library(model.parametric, "joints_and_forces")[0]
    values = joints_and_forces(x=state, u=u, p=model.parameters)
    return {name: np.array(value) for name, value in values.items()}


def moving_with_the_top(model: CableModel, state: np.ndarray, u: np.ndarray) -> np.ndarray:
    """The state in the same shape, moving as the top does under the inputs ``u``.

    Every element translates with the lower end of the top element: the top's velocity less the
    winch's pay-out along the top element's axis (stretched with the line in an elastic rope, whose
    strain holds still). The bonds then hold at velocity level too, so a run whose top starts
    moving (a heave) starts consistently; a top at rest leaves the state as it is.

    Parameters
    ----------
    model : CableModel
    state : array (state_size,)
        A state at rest, e.g. an equilibrium's.
    u : array (15,)
        The inputs at the start.
    """
    q, _ = model.coordinates(state)
    top_axis = np.array(axis_direction(q[-1][3], q[-1][4])).ravel()
    moving = np.array(state, dtype=float)
    half = model.state_size // 2
    stretch = 1 + moving[half - 1] if model.axial else 1.0
    velocity = u[INPUTS.top_velocity] - u[INPUTS.top_length_rate] * stretch * top_axis
    for i in range(model.element_count):
        start = half + i * model.dofs
        moving[start : start + 3] = velocity
    return moving


def starting_state(model: CableModel, drive: Drive, compiled: bool = False) -> np.ndarray:
    """Where every run of a drive starts: its static equilibrium at t = 0, moving with the top.

    The equilibrium under the inputs at t = 0 (:func:`equilibrium`), then
    :func:`moving_with_the_top`, so that a top already moving at t = 0 (a heave) keeps the bonds
    from the first step. One definition for simulations, optimisation models and plants.

    Parameters
    ----------
    model : CableModel
    drive : Drive
    compiled : bool
        See :func:`equilibrium`.
    """
    start = drive.inputs(np.zeros(1))[:, 0]
    # The state depends on the model and the inputs at t = 0 alone: the runs that verify and
    # correct an optimised winch (which starts every profile at the same angle) share it.
    known = model.memo(("starting_states",), dict)
    key = (start.tobytes(), compiled)
    if key not in known:
        rest = equilibrium(model, drive, compiled=compiled).state
        state = moving_with_the_top(model, rest, start)
        if len(known) >= STARTING_STATES_KEPT:
            known.pop(next(iter(known)))
        known[key] = state
    return known[key].copy()


def bond_tensions(model: CableModel, state: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Signed bond tensions (n+1,), N: positive pulls, negative pushes.

    Bond ``j`` joins the upper end of element ``j`` to the element above (``j = n``: the top);
    its tension is the bond force along the axis of element ``j`` (``model.outputs`` gives only
    the norm).
    """
    outputs = model.output_values(state, u)
    return signed_tensions(outputs["joints"], outputs["bond_forces"])


def check_physical(model: CableModel, found: Equilibrium) -> None:
    """Raise :class:`EquilibriumError` unless an equilibrium is one a cable can hang in.

    Every bond must pull (a chain of rods can also balance standing up in compression, a root
    that Newton's method reaches from a poor guess), and a cable heavier than water with no upward
    load (end force, payload, current all without an upward part) must hang with its free end below
    the top.

    Parameters
    ----------
    model : CableModel
    found : Equilibrium
        A root of the static equations, with its joints and signed tensions.
    """
    spec, joints, tensions, u = model.spec, found.joints, found.tensions, found.inputs
    weight_in_air = spec.element.mass_per_length * spec.gravity * spec.cable_length
    scale = max(float(np.abs(tensions).max()), weight_in_air)
    pushing = np.flatnonzero(tensions < -COMPRESSION_TOLERANCE * scale)
    remedy = (
        "Give a guess state near the hanging shape (guess=..., e.g. the equilibrium of the same "
        "scene in a weaker current) or reduce the current."
    )
    if pushing.size:
        worst = pushing[np.argmin(tensions[pushing])]
        raise EquilibriumError(
            f"bond {worst} in compression ({tensions[worst]:.3g} N; {pushing.size} of "
            f"{tensions.size} bonds push): the equilibrium is not physical. {remedy}"
        )
    hydro = spec.element.hydro
    hangs = (
        spec.element.submerged_weight_per_length > 0
        and spec.payload_weight >= 0
        and u[INPUTS.end_force][2] <= 0
        and (hydro is None or hydro.current[2] <= 0)
    )
    if hangs and joints[2, 0] >= joints[2, -1]:
        raise EquilibriumError(
            f"the free end is {joints[2, 0] - joints[2, -1]:.3g} m above the top although the "
            "cable is heavier than water and nothing lifts it: the equilibrium is not physical. "
            f"{remedy}"
        )


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
    """Newton's method with a forward-difference Jacobian on the compiled structured rhs.

    Each step is halved until the residual's 2-norm falls (Armijo), as CasADi's Newton does: a
    full step from the string guess can overshoot where bending bends the free end away from it
    (hanging in a 10 m/s current, n = 100: the full steps wander, the halved ones converge in 7).
    """
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
        step = -np.linalg.solve(jacobian, residual)
        norm = np.linalg.norm(residual)
        for fraction in 0.5 ** np.arange(LINE_SEARCH_HALVINGS):
            trial = np.array(rhs(state_of(solution + fraction * step), u)).ravel()[index]
            if np.linalg.norm(trial) <= (1 - 1e-4 * fraction) * norm:
                break
        solution = solution + fraction * step
    return solution, left


def check_scene_start(scene) -> None:
    """Refuse a scene whose end starts off its bathymetry grid or under its seabed.

    Only an absolute seabed (a grid) can put the start there; the scene's statics are all it
    costs, so an optimiser calls it before any heavy work, as ``simulate`` and ``mpc`` check the
    start they compute anyway.

    Raises
    ------
    OffGridError
        The hanging end's position off the grid or under the seabed, naming ``seabed.grid``.
    """
    if not scene.seabed.absolute:
        return
    start = starting_state(CableModel.from_scene(scene), Drive.from_scene(scene))
    check_start(scene.seabed, start[:3])
