"""The pieces the rigid and the elastic structured graphs share (:mod:`cable_ocp.model.structured`).

Both graphs take the same inputs, add the same bending-joint forces to their elements and end the
block Thomas solve with the same backward sweep; each kernel set (``kernels``) brings its own
Functions for them, with one column (rigid) or two (elastic) per element.
"""

from __future__ import annotations

import casadi as ca

from cable_ocp.model.joints import top_bond_kernel
from cable_ocp.model.kkt import inverse_3x3
from cable_ocp.model.layout import INPUT_SIZE


def graph_inputs(model) -> tuple[ca.MX, ca.MX, ca.MX]:
    """The MX symbols ``x`` (the state), ``u`` (the inputs) and ``p`` (the model's numbers)."""
    x, u = ca.MX.sym("x", model.state_size), ca.MX.sym("u", INPUT_SIZE)
    return x, u, ca.MX.sym("p", model.p.numel())


def column(matrix: ca.MX, k: int, width: int = 1) -> ca.MX:
    """The ``k``-th block of ``width`` columns of ``matrix``."""
    return matrix[:, k * width : (k + 1) * width]


def joint_springs(kernels, q: ca.MX, qd: ca.MX, p_kernel: ca.MX) -> ca.MX:
    """Each element's generalised force from the bending joints at its two ends.

    Parameters
    ----------
    kernels
        The graph's kernels: their ``joint`` Function is mapped over the ``n`` joints.
    q, qd : MX (dofs, n+1)
        The elements' coordinates and their rates, one column an element.
    p_kernel : MX
        The kernels' numbers.
    """
    dofs, count = q.size1(), q.size2()
    lower_forces, upper_forces = kernels.map("joint", count - 1)(
        q[:, :-1], q[:, 1:], qd[:, :-1], qd[:, 1:], p_kernel
    )
    zero = ca.MX.zeros(dofs, 1)
    return ca.horzcat(lower_forces, zero) + ca.horzcat(zero, upper_forces)


def backward_sweep(kernels, final: ca.MX, packed: ca.MX, upper: ca.MX) -> ca.MX:
    """The bond forces of every bond, the block Thomas solve's backward sweep from the top one's.

    Parameters
    ----------
    kernels
        The graph's kernels: their ``backward`` step is accumulated down the chain.
    final : MX
        The top bond's forces (a column).
    packed : MX
        The forward sweep's packed result, one column a bond (the top one last).
    upper : MX
        The upper off-diagonal 3 x 3 blocks side by side, one a bond below the top.

    Returns
    -------
    MX, one column a bond from the bottom up
    """
    last = packed.size2() - 1
    backwards = list(range(last - 1, -1, -1))
    reverse_upper = ca.horzcat(*[upper[:, 3 * j : 3 * j + 3] for j in backwards])
    reverse_packed = ca.horzcat(*[packed[:, j] for j in backwards])
    solved = kernels.mapaccum("backward", last)(final, reverse_packed, reverse_upper)
    return ca.horzcat(*[solved[:, k] for k in range(last - 1, -1, -1)], final)


def shared_kernels(model, dofs: int, columns: int, prefix: str = "") -> dict[str, ca.Function]:
    """The kernels the rigid and the elastic loops build alike, by their field of ``Kernels``.

    The top bond's (:func:`~cable_ocp.model.joints.top_bond_kernel`), one step of each sweep of
    the block Thomas solve, the accelerations from the bond forces, a 3 x 3 inverse and the
    segment length ``Delta`` (m) from ``p``.

    Parameters
    ----------
    model : ParametricModel
    dofs : int
        Coordinates per element.
    columns : int
        Right-hand sides the solve carries: 1 (rigid), 2 (elastic: the chain's forces and its
        answer to a unit strain acceleration).
    prefix : str
        Put before the sweeps' and the accelerations' Function names.
    """
    matrix = ca.SX.sym("m", 3, 3)
    return {
        "top_bond": top_bond_kernel(model),
        "forward": _forward_sweep(f"{prefix}forward", columns),
        "backward": _backward_sweep(f"{prefix}backward", columns),
        "accelerations": _accelerations(f"{prefix}acc", dofs, columns),
        "inverse": ca.Function("inverse", [matrix], [inverse_3x3(matrix)]),
        "segment_length": ca.Function("segment_length", [model.p], [model.spec.segment_length]),
    }


def _forward_sweep(name: str, columns: int) -> ca.Function:
    """One forward step of the block Thomas solve; accumulator ``[vec(S^-1); vec(reduced)]``."""
    previous = ca.SX.sym("previous", 9 + 3 * columns)
    inverse, reduced = ca.reshape(previous[:9], 3, 3), ca.reshape(previous[9:], 3, columns)
    lower, upper = ca.SX.sym("lower", 3, 3), ca.SX.sym("upper", 3, 3)
    diag, rhs = ca.SX.sym("diag", 3, 3), ca.SX.sym("rhs", 3, columns)
    factor = lower @ inverse
    new_inverse = inverse_3x3(diag - factor @ upper)
    new_reduced = rhs - factor @ reduced
    return ca.Function(
        name,
        [previous, lower, upper, diag, rhs],
        [ca.vertcat(ca.vec(new_inverse), ca.vec(new_reduced))],
    )


def _backward_sweep(name: str, columns: int) -> ca.Function:
    """One back substitution: ``lambda_j = S_j^-1 (reduced_j - U_j lambda_{j+1})`` (vec)."""
    above = ca.SX.sym("above", 3 * columns)
    packed, upper = ca.SX.sym("packed", 9 + 3 * columns), ca.SX.sym("upper", 3, 3)
    inverse, reduced = ca.reshape(packed[:9], 3, 3), ca.reshape(packed[9:], 3, columns)
    solved = inverse @ (reduced - upper @ ca.reshape(above, 3, columns))
    return ca.Function(name, [above, packed, upper], [ca.vec(solved)])


def _accelerations(name: str, dofs: int, columns: int) -> ca.Function:
    """Each element's accelerations from its free ones and the bond forces at its two ends."""
    free, along_p = ca.SX.sym("free", dofs, columns), ca.SX.sym("p", dofs, 3)
    along_d = ca.SX.sym("d", dofs, 3)
    own, below = ca.SX.sym("own", 3, columns), ca.SX.sym("below", 3, columns)
    return ca.Function(
        name, [free, along_p, along_d, own, below], [free - along_d @ own + along_p @ below]
    )
