"""The right-hand side as loops over small per-element Functions, for compiling to C.

:attr:`CableModel.rhs` is one flat SX expression: right for inspection and symbolic Jacobians, but
compiled to C it is straight-line code that grows with ``n`` (about 1 MB of machine code and
minutes of gcc at n = 100). :func:`structured_rhs` computes the same ``x'`` from four small SX
Functions evaluated in loops (CasADi ``map`` and ``mapaccum`` in an MX graph): the element terms,
the bending joints, the bond blocks and one step of each sweep of the block Thomas solve
(:mod:`cable_ocp.model.kkt`). The generated C holds each of them once, so it compiles in seconds at
any ``n`` and stays in the processor's caches. 5-DOF models only (torsion couples neighbouring
rotations, which these Functions do not carry); :func:`supports` tells.

The Functions are built on a :class:`~cable_ocp.model.parametric.ParametricModel` and take its
numbers as the last input ``p``; :func:`compiled_structured` binds a scene's numbers to the compiled
library.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

import casadi as ca

from cable_ocp.model.axial_structured import (
    ElasticKernels,
    elastic_kernels_of,
    elastic_structured_graph,
)
from cable_ocp.model.cable import CableModel
from cable_ocp.model.compile import (
    CompileReport,
    Library,
    compile_in_background,
    compiled_from,
)
from cable_ocp.model.joints import Kernels, baumgarte, bending_energies
from cable_ocp.model.kinematics import POSITION
from cable_ocp.model.kkt import cholesky_solve
from cable_ocp.model.layout import INPUTS, top_inputs
from cable_ocp.model.parametric import ModelLayout, ParametricModel
from cable_ocp.model.rfe import element_functions
from cable_ocp.model.rk4 import parametric_rk4_step
from cable_ocp.model.structured_parts import (
    backward_sweep,
    column,
    graph_inputs,
    joint_springs,
    shared_kernels,
)


def supports(model: ModelLayout) -> bool:
    """Whether :func:`structured_rhs` can build this model's right-hand side (5 DOF, n >= 2).

    An elastic rope's loops are those of :mod:`cable_ocp.model.axial_structured`.
    """
    return not model.spec.element.torsion and model.spec.elements >= 2


def _element_solve(model: ParametricModel, end: bool) -> ca.Function:
    """Element terms with ``M^-1`` applied: ``q, q', l, spring force (, end force), p`` -> blocks.

    Outputs ``free = M^-1 f``, ``along_p = M^-1 P^T``, ``along_d = M^-1 D^T``, ``D``, the upper
    point ``A_i + l e`` and its rate, ``l e''`` (the quadratic part), ``e`` and ``e'``.
    """
    dofs, p = model.dofs, model.p
    element, _ = element_functions(model.spec.element, p)
    q, qd = ca.SX.sym("q", dofs), ca.SX.sym("qd", dofs)
    length, spring = ca.SX.sym("length"), ca.SX.sym("spring", dofs)
    mass, force, axis, axis_rate, quadratic, top = element(q, qd, length, p)
    force = force + spring
    inputs = [q, qd, length, spring]
    if end:
        end_force = ca.SX.sym("end_force", 3)
        mass, force = model.end_loads(mass, force, q, qd, end_force)
        inputs.append(end_force)
    inputs.append(p)
    select = ca.SX(ca.DM.eye(dofs)[:3, :])
    solved = cholesky_solve(mass, ca.horzcat(force, select.T, top.T))
    outputs = [
        solved[:, 0],
        solved[:, 1:4],
        solved[:, 4:7],
        top,
        q[POSITION] + length * axis,
        qd[POSITION] + length * axis_rate,
        length * quadratic,
        axis,
        axis_rate,
    ]
    return ca.Function("element_end" if end else "element", inputs, outputs, {"cse": True})


def _joint_forces(model: ParametricModel) -> ca.Function:
    """Generalised bending forces on the two elements of a joint (from its energy, as the model)."""
    dofs, p = model.dofs, model.p
    element, _ = element_functions(model.spec.element, p)
    q = [ca.SX.sym(f"q{k}", dofs) for k in range(2)]
    qd = [ca.SX.sym(f"qd{k}", dofs) for k in range(2)]
    unit = ca.SX(1.0)  # the axis and its rate do not depend on the length
    axes, rates = zip(*[element(q[k], qd[k], unit, p)[2:4] for k in range(2)], strict=True)
    potential, dissipation = bending_energies(axes[0], axes[1], rates[0], rates[1], model.spec)
    forces = [-ca.gradient(potential, q[k]) - ca.gradient(dissipation, qd[k]) for k in range(2)]
    return ca.Function("joint", [*q, *qd, p], forces, {"cse": True})


def _bond_blocks(model: ParametricModel) -> ca.Function:
    """Blocks of bond ``j`` between elements ``j-1`` (below) and ``j`` (above), with Baumgarte."""
    dofs = model.dofs
    select = ca.SX(ca.DM.eye(dofs)[:3, :])
    free_b, free_a = ca.SX.sym("free_b", dofs), ca.SX.sym("free_a", dofs)
    along_d_b, along_p_a = ca.SX.sym("along_d_b", dofs, 3), ca.SX.sym("along_p_a", dofs, 3)
    along_d_a = ca.SX.sym("along_d_a", dofs, 3)
    top_b, top_a = ca.SX.sym("top_b", 3, dofs), ca.SX.sym("top_a", 3, dofs)
    point_b, rate_b, quad_b = (ca.SX.sym(name, 3) for name in ("point_b", "rate_b", "quad_b"))
    position_a, velocity_a = ca.SX.sym("position_a", 3), ca.SX.sym("velocity_a", 3)
    bond_rhs = baumgarte(quad_b, velocity_a - rate_b, position_a - point_b, model.spec)
    inputs = [free_b, along_d_b, top_b, point_b, rate_b, quad_b]
    inputs += [free_a, along_p_a, along_d_a, top_a, position_a, velocity_a, model.p]
    outputs = [
        top_b @ along_d_b + select @ along_p_a,
        bond_rhs + top_b @ free_b - select @ free_a,
        -select @ along_d_a,
        -top_a @ along_p_a,
    ]
    return ca.Function("bond", inputs, outputs, {"cse": True})


def structured_rhs(model: ParametricModel) -> ca.Function:
    """``(x, u, p) -> x'``, equal to ``model.rhs``, as loops over per-element Functions (MX).

    Raises
    ------
    ValueError
        For a model :func:`supports` rejects.
    """
    return _graph_function(model, "rhs", "rhs", lambda g: {"xdot": g.xdot})


def structured_outputs(model: ParametricModel) -> ca.Function:
    """``(x, u, p) ->`` joints (3 x n+2, m) and bond tensions (n+1, N), as ``model.outputs``.

    What a :class:`~cable_ocp.simulation.trajectory.Trajectory` keeps of every sample, computed by
    the same loops as :func:`structured_rhs` so that it compiles in seconds at any ``n``.
    """
    return _graph_function(
        model,
        "outputs",
        "joints_tensions",
        lambda g: {"joints": g.joints, "tensions": ca.sqrt(ca.sum1(g.forces**2)).T},
    )


def structured_joints_and_forces(model: ParametricModel) -> ca.Function:
    """``(x, u, p) ->`` joints (3 x n+2, m) and bond forces (3 x n+1, N), as ``model.outputs``.

    By the loops of :func:`structured_rhs` (a static equilibrium's tensions, without the flat
    graph of ``model.outputs``: 1 s at n = 100); compiled with the rest of the structure's
    library (:func:`compiled_library`), so that a cache hit builds no graph at all.
    """
    return _graph_function(
        model,
        "joints_bond_forces",
        "joints_bond_forces",
        lambda g: {"joints": g.joints, "bond_forces": g.forces},
    )


def structured_bond_residual(model: ParametricModel) -> ca.Function:
    """``(x, u, p) ->`` the bond residuals ``Phi`` (3 (n+1), m), as ``model.bond_residual()``.

    By the loops of :func:`structured_rhs`, so that a run integrated with them checks its bonds
    without the flat graph (1 s to build at n = 100).
    """
    return _graph_function(
        model, "bond_residual", "bond_residual", lambda g: {"bond_residual": ca.vec(g.residual)}
    )


def compiled_structured(model: CableModel, which: str, count: int | None = None) -> ca.Function:
    """A structured Function of ``(x, u)`` with the model's numbers bound, compiled to C.

    ``which`` is ``"rhs"`` (:func:`structured_rhs`) or ``"outputs"`` (:func:`structured_outputs`);
    with ``count``, it is mapped over that many states and inputs (columns). The library, without
    derivatives, is compiled (or loaded from the disk cache) once per structure and process; the
    bound Function once per model.
    """
    parametric = model.parametric
    library = compiled_library(parametric, which)[0]
    mapped = parametric.memo(
        ("structured", which, "compiled", count),
        lambda: library if count is None else library.map(count),
    )
    return model.memo(("structured", which, "compiled", count), lambda: model.bind(mapped))


def structured_rk4_step(model: ParametricModel) -> ca.Function:
    """``(x, stage_inputs, p, h) ->`` the state after one RK4 step of :func:`structured_rhs`.

    In the structure's library beside the right-hand side, the step is one C function calling
    it four times: 7 % faster per step at n = 15 than the four calls made from CasADi's virtual
    machine, for no more compile time.
    """
    return model.memo(
        ("structured", "rk4_step"), lambda: parametric_rk4_step(model, structured_rhs(model))
    )


def structured_bond_norm(model: ParametricModel) -> ca.Function:
    """``(x, u, p) ->`` the largest bond residual (m), by the loops of :func:`structured_rhs`."""

    def build() -> ca.Function:
        residual_function = structured_bond_residual(model)
        x, u, p = (residual_function.mx_in(k) for k in range(3))
        norm = ca.mmax(ca.fabs(residual_function(x, u, p)))
        return ca.Function("bond_norm", [x, u, p], [norm], ["x", "u", "p"], ["norm"], {"cse": True})

    return model.memo(("structured", "bond_norm"), build)


# The structure's Functions compiled into one library: each one's name and what builds it.
LIBRARY = {
    "rhs": ("rhs", structured_rhs),
    "rk4_step": ("rk4_step", structured_rk4_step),
    "outputs": ("joints_tensions", structured_outputs),
    "bond_norm": ("bond_norm", structured_bond_norm),
    "joints_and_forces": ("joints_bond_forces", structured_joints_and_forces),
}


def compiled_library(model: ParametricModel, which: str) -> tuple[ca.Function, CompileReport]:
    """The structure's ``(x, u, p)`` Function ``which`` (a key of :data:`LIBRARY`), compiled to C.

    The right-hand side, the outputs and the bond check of a structure share one library (they
    call the same element Functions, compiled once), without derivatives, from the disk cache
    when possible; once per structure and process. The compiled RK4 step of a 5-DOF model calls
    this right-hand side too (:func:`cable_ocp.simulation.integrate.compiled_parametric_step`),
    so the statics and the simulations of a structure share it.
    """

    def compile_library() -> tuple[dict[str, ca.Function], CompileReport]:
        functions, report = compiled_from(_library(model))
        return dict(zip(LIBRARY, functions, strict=True)), report

    functions, report = model.memo(("structured", "compiled"), compile_library)
    return functions[which], report


def compile_library_in_background(model: ParametricModel) -> None:
    """Start compiling the library of :func:`compiled_library` if it is not in the cache.

    The C compiler runs while the caller goes on
    (:func:`cable_ocp.model.compile.compile_in_background`); a model the structured loops do
    not support is left alone.
    """
    if supports(model):
        compile_in_background(_library(model))


def _library(model: ParametricModel) -> Library:
    """The structure's library of :func:`~cable_ocp.model.compile.compiled_from`."""
    return Library(
        lambda: [build(model) for _, build in LIBRARY.values()],
        [name for name, _ in LIBRARY.values()],
        f"{model.structure!r}|structured right-hand side, outputs and bond check",
        False,
    )


def _shared_graph(model: ParametricModel) -> tuple[ca.MX, ...]:
    """:func:`structured_graph`, built once per model for the right-hand side and the outputs."""
    return model.memo(("structured", "graph"), lambda: structured_graph(model, kernels_of(model)))


class _GraphParts(NamedTuple):
    """What :func:`structured_graph` gives beside ``(x, u, p)``, by name."""

    xdot: ca.MX
    forces: ca.MX
    joints: ca.MX
    residual: ca.MX


def _graph_function(
    model: ParametricModel,
    key: str,
    name: str,
    outputs: Callable[[_GraphParts], dict[str, ca.MX]],
) -> ca.Function:
    """``(x, u, p) ->`` the named ``outputs`` of the model's shared graph.

    Parameters
    ----------
    model : ParametricModel
    key : str
        The Function is kept in the model's memo under ``("structured", key)``.
    name : str
        The Function's name.
    outputs : callable
        From the graph's parts to the outputs, by name and in order.
    """

    def build() -> ca.Function:
        x, u, p, *rest = _shared_graph(model)
        named = outputs(_GraphParts(*rest))
        return ca.Function(name, [x, u, p], list(named.values()), ["x", "u", "p"], list(named))

    return model.memo(("structured", key), build)


def kernels_of(model: ParametricModel) -> Kernels | ElasticKernels:
    """The structured loops' Functions of ``model`` itself (SX, interpreted until compiled)."""
    if model.axial:
        return elastic_kernels_of(model)
    return Kernels(
        joint=_joint_forces(model),
        element=_element_solve(model, end=False),
        element_end=_element_solve(model, end=True),
        bond=_bond_blocks(model),
        **shared_kernels(model, model.dofs, 1),
    )


def structured_graph(model: ModelLayout, kernels: Kernels | ElasticKernels) -> tuple[ca.MX, ...]:
    """Inputs ``x, u, p`` and the MX expressions of ``x'``, bond forces, joints, bond residuals.

    ``model`` gives the layout (``n``, the state's size, the size of ``p``), ``kernels`` the
    Functions evaluated in its loops.
    """
    if not supports(model):
        raise ValueError("the structured right-hand side needs 5-DOF elements and n >= 2")
    if model.axial:
        return elastic_structured_graph(model, kernels)
    dofs, count = model.dofs, model.element_count
    size = dofs * count
    x, u, p = graph_inputs(model)
    q = ca.reshape(x[:size], dofs, count)
    qd = ca.reshape(x[size:], dofs, count)
    top, top_velocity, top_acceleration, top_length, top_length_rate, top_length_acc = top_inputs(u)
    delta = kernels.segment_length(p)
    p_kernel = kernels.parameters(p)
    spring = joint_springs(kernels, q, qd, p_kernel)

    lengths = ca.horzcat(ca.repmat(delta, 1, count - 2), top_length)
    rest = kernels.map("element", count - 1)(q[:, 1:], qd[:, 1:], lengths, spring[:, 1:], p_kernel)
    first = kernels.element_end(
        q[:, 0], qd[:, 0], delta / 2, spring[:, 0], u[INPUTS.end_force], p_kernel
    )
    free, along_p, along_d, top_jac, point, rate, quad, axis, axis_rate = (
        ca.horzcat(a, b) for a, b in zip(first, rest, strict=True)
    )

    interior = kernels.map("bond", count - 1)(
        free[:, :-1], along_d[:, : 3 * (count - 1)], top_jac[:, : dofs * (count - 1)],
        point[:, :-1], rate[:, :-1], quad[:, :-1],
        free[:, 1:], along_p[:, 3:], along_d[:, 3:], top_jac[:, dofs:],
        q[0:3, 1:], qd[0:3, 1:], p_kernel,
    )  # fmt: skip
    diag_in, rhs_in, upper, lower = interior
    last = count - 1
    top_rate = column(rate, last) + top_length_rate * column(axis, last)
    top_quad = (
        column(quad, last)
        + top_length_acc * column(axis, last)
        + 2 * top_length_rate * column(axis_rate, last)
        - top_acceleration
    )
    top_rhs = kernels.top_bond(
        top_quad, top_velocity - top_rate, top - column(point, last), p_kernel
    ) + column(top_jac, last, dofs) @ column(free, last)
    diag = ca.horzcat(diag_in, column(top_jac, last, dofs) @ column(along_d, last, 3))
    rhs = ca.horzcat(rhs_in, top_rhs)

    start = ca.vertcat(ca.vec(kernels.inverse(diag[:, 0:3])), rhs[:, 0])
    sweep = kernels.mapaccum("forward", count - 1)(start, lower, upper, diag[:, 3:], rhs[:, 1:])
    packed = ca.horzcat(start, sweep)
    final = ca.reshape(packed[:9, last], 3, 3) @ packed[9:, last]
    forces = backward_sweep(kernels, final, packed, upper)
    below = ca.horzcat(ca.MX.zeros(3, 1), forces[:, :-1])
    qdd = kernels.map("accelerations", count)(free, along_p, along_d, forces, below)
    joints = ca.horzcat(q[0:3, :], column(point, last))
    residual = ca.horzcat(q[0:3, 1:], top) - point  # each bond's lower point less its upper one
    return x, u, p, ca.vertcat(x[size:], ca.vec(qdd)), forces, joints, residual
