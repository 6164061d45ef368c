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


def shared_kernels(model) -> dict[str, ca.Function]:
    """The kernels the rigid and the elastic loops build alike, by their field of ``Kernels``.

    The top bond's (:func:`~cable_ocp.model.joints.top_bond_kernel`), a 3 x 3 inverse and the
    segment length ``Delta`` (m) from ``p``.
    """
    matrix = ca.SX.sym("m", 3, 3)
    return {
        "top_bond": top_bond_kernel(model),
        "inverse": ca.Function("inverse", [matrix], [inverse_3x3(matrix)]),
        "segment_length": ca.Function("segment_length", [model.p], [model.spec.segment_length]),
    }
