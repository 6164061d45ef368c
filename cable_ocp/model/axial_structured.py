"""The elastic rope's right-hand side as loops over small per-element Functions, for compiling.

The same equations as :func:`cable_ocp.model.axial.elastic_graph` (the rigid chain bordered by the
line's strain, two right-hand sides through the block Thomas solve), arranged as
:mod:`cable_ocp.model.structured` arranges the rigid chain's: element, joint and bond kernels and
the two sweeps of the elimination, evaluated in CasADi ``map`` and ``mapaccum`` loops, so that the
generated C holds each kernel once and compiles in seconds at any ``n``. Every kernel carries two
columns where the rigid one carries one: the chain's own forces (``A``) and its answer to a unit
strain acceleration (``B``); sums over the elements then give the strain's equation.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from cable_ocp.model.axial_element import elastic_element_functions
from cable_ocp.model.joints import Kernels, baumgarte, bending_energies
from cable_ocp.model.kinematics import axis_direction
from cable_ocp.model.kkt import cholesky_solve
from cable_ocp.model.layout import INPUTS, top_inputs
from cable_ocp.model.structured_parts import (
    backward_sweep,
    column,
    graph_inputs,
    joint_springs,
    shared_kernels,
)

DOFS = 5  # an elastic rope's elements are 5-DOF
COLUMNS = 2  # right-hand sides: the chain's forces (A), a unit strain acceleration (B)


def _select() -> ca.SX:
    return ca.SX(ca.DM.eye(DOFS)[:3, :])  # P = [I 0]


def _element_solve(model, end: bool) -> ca.Function:
    """Element terms with ``M^-1`` applied (the strain an input): the blocks of the sweeps."""
    p = model.p
    element, _ = elastic_element_functions(model.spec.element, p)
    q, qd = ca.SX.sym("q", DOFS), ca.SX.sym("qd", DOFS)
    strain, strain_rate = ca.SX.sym("s"), ca.SX.sym("sd")
    length, spring = ca.SX.sym("length"), ca.SX.sym("spring", DOFS)
    local, local_rate = ca.vertcat(q, strain), ca.vertcat(qd, strain_rate)
    mass6, force6, axis, axis_rate, point, jacobian, quadratic = element(
        local, local_rate, length, p
    )
    mass, coupling = mass6[:DOFS, :DOFS], mass6[:DOFS, DOFS]
    force = force6[:DOFS] + spring
    inputs = [q, qd, strain, strain_rate, length, spring]
    if end:
        end_force = ca.SX.sym("end_force", 3)
        mass, force = model.end_loads(mass, force, q, qd, end_force)
        inputs.append(end_force)
    inputs.append(p)
    top = jacobian[:, :DOFS]
    solved = cholesky_solve(mass, ca.horzcat(force, -coupling, _select().T, top.T))
    outputs = [
        solved[:, :COLUMNS],
        solved[:, COLUMNS : COLUMNS + 3],
        solved[:, COLUMNS + 3 : COLUMNS + 6],
        top,
        jacobian[:, DOFS],
        coupling,
        mass6[DOFS, DOFS],
        force6[DOFS],
        point,
        jacobian @ local_rate,
        quadratic,
        axis,
        axis_rate,
    ]
    name = "elastic_element_end" if end else "elastic_element"
    return ca.Function(name, inputs, outputs, {"cse": True})


def _joint_forces(model) -> ca.Function:
    """Generalised bending forces on the two elements of a joint (the rigid model's)."""
    q = [ca.SX.sym(f"q{k}", DOFS) for k in range(2)]
    qd = [ca.SX.sym(f"qd{k}", DOFS) for k in range(2)]
    axes = [axis_direction(qk[3], qk[4]) for qk in q]
    rates = [ca.jtimes(a, qk, qdk) for a, qk, qdk in zip(axes, q, qd, strict=True)]
    potential, dissipation = bending_energies(axes[0], axes[1], rates[0], rates[1], model.spec)
    forces = [-ca.gradient(potential, q[k]) - ca.gradient(dissipation, qd[k]) for k in range(2)]
    return ca.Function("elastic_joint", [*q, *qd, model.p], forces, {"cse": True})


def _bond_blocks(model) -> ca.Function:
    """Blocks of bond ``j`` between elements ``j-1`` (below) and ``j`` (above), two columns."""
    select = _select()
    free_b, free_a = ca.SX.sym("free_b", DOFS, COLUMNS), ca.SX.sym("free_a", DOFS, COLUMNS)
    along_d_b, along_p_a = ca.SX.sym("along_d_b", DOFS, 3), ca.SX.sym("along_p_a", DOFS, 3)
    along_d_a = ca.SX.sym("along_d_a", DOFS, 3)
    top_b, top_a = ca.SX.sym("top_b", 3, DOFS), ca.SX.sym("top_a", 3, DOFS)
    strain_b = ca.SX.sym("strain_b", 3)
    point_b, rate_b, quad_b = (ca.SX.sym(name, 3) for name in ("point_b", "rate_b", "quad_b"))
    position_a, velocity_a = ca.SX.sym("position_a", 3), ca.SX.sym("velocity_a", 3)
    bond_rhs = baumgarte(quad_b, velocity_a - rate_b, position_a - point_b, model.spec)
    inputs = [free_b, along_d_b, top_b, strain_b, point_b, rate_b, quad_b]
    inputs += [free_a, along_p_a, along_d_a, top_a, position_a, velocity_a, model.p]
    outputs = [
        top_b @ along_d_b + select @ along_p_a,
        ca.horzcat(bond_rhs, strain_b) + top_b @ free_b - select @ free_a,
        -select @ along_d_a,
        -top_a @ along_p_a,
    ]
    return ca.Function("elastic_bond", inputs, outputs, {"cse": True})


@dataclass(frozen=True)
class ElasticKernels(Kernels):
    """The kernels of the elastic loops, with ``axial``: ``p`` -> ``EA`` (N), damping ratio.

    Those of :class:`~cable_ocp.model.joints.Kernels`, with two columns where the rigid ones
    carry one.
    """

    axial: ca.Function | None = None


def elastic_kernels_of(model) -> ElasticKernels:
    """The elastic loops' Functions of ``model`` itself (a parametric model with a strain)."""
    spec = model.spec
    return ElasticKernels(
        joint=_joint_forces(model),
        element=_element_solve(model, end=False),
        element_end=_element_solve(model, end=True),
        bond=_bond_blocks(model),
        **shared_kernels(model, DOFS, COLUMNS, prefix="elastic_"),
        axial=ca.Function("axial", [model.p], [spec.axial_stiffness, spec.axial_damping]),
    )


def _columns(matrix: ca.MX, width: int, count: int) -> tuple[ca.MX, ca.MX]:
    """Split ``count`` blocks of ``width`` x 2 side by side into their A and B columns."""
    stacked = ca.reshape(matrix, width * COLUMNS, count)
    return stacked[:width, :], stacked[width:, :]


def _total(matrix: ca.MX) -> ca.MX:
    return ca.sum2(ca.sum1(matrix))


def elastic_structured_graph(model, kernels: ElasticKernels) -> tuple[ca.MX, ...]:
    """Inputs ``x, u, p`` and the MX expressions of ``x'``, bond forces, joints, bond residuals.

    As :func:`cable_ocp.model.structured.structured_graph`, for a model with the strain.
    """
    count = model.element_count
    size = DOFS * count
    x, u, p = graph_inputs(model)
    q = ca.reshape(x[:size], DOFS, count)
    strain, strain_rate = x[size], x[2 * size + 1]
    qd = ca.reshape(x[size + 1 : 2 * size + 1], DOFS, count)
    top, top_velocity, top_acceleration, top_length, top_length_rate, top_length_acc = top_inputs(u)
    delta = kernels.segment_length(p)
    axial_stiffness, damping_ratio = kernels.axial(p)
    p_kernel = kernels.parameters(p)
    spring = joint_springs(kernels, q, qd, p_kernel)

    lengths = ca.horzcat(ca.repmat(delta, 1, count - 2), top_length)
    strains = ca.repmat(strain, 1, count - 1)
    strain_rates = ca.repmat(strain_rate, 1, count - 1)
    rest = kernels.map("element", count - 1)(
        q[:, 1:], qd[:, 1:], strains, strain_rates, lengths, spring[:, 1:], p_kernel
    )
    first = kernels.element_end(
        q[:, 0], qd[:, 0], strain, strain_rate, delta / 2, spring[:, 0], u[INPUTS.end_force],
        p_kernel,
    )  # fmt: skip
    blocks = [ca.horzcat(a, b) for a, b in zip(first, rest, strict=True)]
    free, along_p, along_d, top_jac, strain_jac, coupling = blocks[:6]
    strain_mass, strain_force, point, rate, quad, axis, axis_rate = blocks[6:]

    last = count - 1
    interior = kernels.map("bond", count - 1)(
        free[:, : COLUMNS * last], along_d[:, : 3 * last], top_jac[:, : DOFS * last],
        strain_jac[:, :-1], point[:, :-1], rate[:, :-1], quad[:, :-1],
        free[:, COLUMNS:], along_p[:, 3:], along_d[:, 3:], top_jac[:, DOFS:],
        q[0:3, 1:], qd[0:3, 1:], p_kernel,
    )  # fmt: skip
    diag_in, rhs_in, upper, lower = interior
    stretch = 1 + strain
    top_axis, top_axis_rate = column(axis, last), column(axis_rate, last)
    top_rate = column(rate, last) + top_length_rate * stretch * top_axis
    top_quad = (
        column(quad, last)
        + top_length_acc * stretch * top_axis
        + 2 * top_length_rate * (strain_rate * top_axis + stretch * top_axis_rate)
        - top_acceleration
    )
    top_bond = kernels.top_bond(
        top_quad, top_velocity - top_rate, top - column(point, last), p_kernel
    )
    top_rhs = ca.horzcat(top_bond, column(strain_jac, last)) + column(top_jac, last, DOFS) @ column(
        free, last, COLUMNS
    )
    diag = ca.horzcat(diag_in, column(top_jac, last, DOFS) @ column(along_d, last, 3))
    rhs = ca.horzcat(rhs_in, top_rhs)

    packed_size = 9 + 3 * COLUMNS
    start = ca.vertcat(ca.vec(kernels.inverse(diag[:, 0:3])), ca.vec(column(rhs, 0, COLUMNS)))
    sweep = kernels.mapaccum("forward", last)(start, lower, upper, diag[:, 3:], rhs[:, COLUMNS:])
    packed = ca.horzcat(start, sweep)
    final = ca.vec(
        ca.reshape(packed[:9, last], 3, 3) @ ca.reshape(packed[9:packed_size, last], 3, COLUMNS)
    )
    forces = backward_sweep(kernels, final, packed, upper)  # 6 x count
    forces_a, forces_b = forces[:3, :], forces[3:, :]
    below = ca.horzcat(ca.MX.zeros(3 * COLUMNS, 1), forces[:, :-1])
    qdd = kernels.map("accelerations", count)(
        free, along_p, along_d, ca.reshape(forces, 3, COLUMNS * count),
        ca.reshape(below, 3, COLUMNS * count),
    )  # fmt: skip
    qdd_a, qdd_b = _columns(qdd, DOFS, count)

    line_length = delta / 2 + (count - 2) * delta + top_length
    stiffness = axial_stiffness * line_length
    modal_mass = _total(strain_mass) + _total(coupling * qdd_b) + _total(strain_jac * forces_b)
    damping = 2 * damping_ratio * ca.sqrt(stiffness * modal_mass)
    strain_acceleration = (
        _total(strain_force)
        - stiffness * strain
        - damping * strain_rate
        - _total(coupling * qdd_a)
        - _total(strain_jac * forces_a)
    ) / modal_mass
    accelerations = qdd_a + strain_acceleration * qdd_b
    bond_forces = forces_a + strain_acceleration * forces_b
    xdot = ca.vertcat(x[size + 1 :], ca.vec(accelerations), strain_acceleration)
    joints = ca.horzcat(q[0:3, :], column(point, last))
    residual = ca.horzcat(q[0:3, 1:], top) - point
    return x, u, p, xdot, bond_forces, joints, residual
