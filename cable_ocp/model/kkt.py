"""Solve the bonded equations ``M q'' = f + C^T lambda``, ``C q'' = b`` for ``q''`` and ``lambda``.

The bonds of a chain couple only neighbouring elements and ``M`` is block diagonal, so the Schur
complement ``S = C M^-1 C^T`` is block tridiagonal with 3x3 blocks. :func:`thomas_solve` eliminates
it by the block Thomas algorithm in SX: an O(n) expression that compiles well (CONVENTIONS.md §4).
:func:`sparse_kkt_solve` assembles the whole KKT matrix and solves it with a general sparse solver;
it is kept as an independent cross-check.

Bond ``j`` (1..n) is ``r_j - (r_{j-1} + l_{j-1} e_{j-1}) = 0``; bond ``n+1`` is
``r_top - (r_n + l_n e_n) = 0``. Its Jacobian blocks are ``P = [I 0]`` on element ``j`` and
``-D_{j-1}`` on element ``j-1``, where ``D_i`` is the Jacobian of ``A_{i+1}`` w.r.t. ``q_i``.
"""

from __future__ import annotations

import casadi as ca


def cholesky_solve(matrix: ca.SX, rhs: ca.SX) -> ca.SX:
    """Solve ``matrix @ x = rhs`` for a small symmetric positive definite SX matrix.

    Written out as a Cholesky factorisation so the expression stays short and needs no pivoting.
    """
    size = matrix.shape[0]
    lower = [[None] * size for _ in range(size)]
    for i in range(size):
        for j in range(i + 1):
            total = matrix[i, j] - sum((lower[i][k] * lower[j][k] for k in range(j)), 0)
            lower[i][j] = ca.sqrt(total) if i == j else total / lower[j][j]
    columns = []
    for c in range(rhs.shape[1]):
        y = [None] * size
        for i in range(size):
            y[i] = (rhs[i, c] - sum((lower[i][k] * y[k] for k in range(i)), 0)) / lower[i][i]
        x = [None] * size
        for i in reversed(range(size)):
            tail = sum((lower[k][i] * x[k] for k in range(i + 1, size)), 0)
            x[i] = (y[i] - tail) / lower[i][i]
        columns.append(ca.vertcat(*x))
    return ca.horzcat(*columns)


def inverse_3x3(matrix: ca.SX) -> ca.SX:
    """Inverse of a 3x3 SX matrix by cofactors."""
    m = matrix
    cof = ca.SX(3, 3)
    for i in range(3):
        for j in range(3):
            r = [k for k in range(3) if k != i]
            c = [k for k in range(3) if k != j]
            minor = m[r[0], c[0]] * m[r[1], c[1]] - m[r[0], c[1]] * m[r[1], c[0]]
            cof[i, j] = (-1) ** (i + j) * minor
    det = m[0, 0] * cof[0, 0] + m[0, 1] * cof[0, 1] + m[0, 2] * cof[0, 2]
    return cof.T / det


def thomas_solve(
    mass_blocks: list[ca.SX],
    force_blocks: list[ca.SX],
    top_jacobians: list[ca.SX],
    bond_rhs: list[ca.SX],
) -> tuple[list[ca.SX], list[ca.SX]]:
    """Accelerations and bond forces by block-tridiagonal (Thomas) elimination.

    Parameters
    ----------
    mass_blocks : list of SX (dofs x dofs), one per element 0..n
    force_blocks : list of SX (dofs x k), the generalised forces ``f_i``
    top_jacobians : list of SX (3 x dofs), ``D_i``
    bond_rhs : list of SX (3 x k), ``b_j`` for bonds 1..n+1

    ``k`` right-hand sides are solved together (an elastic rope solves two:
    :mod:`cable_ocp.model.axial`); most solve one.

    Returns
    -------
    accelerations : list of SX (dofs x k), ``q''_i``
    bond_forces : list of SX (3 x k), ``lambda_j`` for bonds 1..n+1 (N)
    """
    count = len(mass_blocks)
    dofs = mass_blocks[0].shape[0]
    columns = force_blocks[0].shape[1]
    select = ca.SX(ca.DM.eye(dofs)[:3, :])  # P = [I 0]
    # One SX Function for the element solve, called per element: CasADi inlines it in C++, where
    # building the Cholesky expression in Python for each of 101 elements took 1.7 s.
    mass_sym, rhs_sym = ca.SX.sym("mass", dofs, dofs), ca.SX.sym("rhs", dofs, columns + 6)
    element_solve = ca.Function("solve", [mass_sym, rhs_sym], [cholesky_solve(mass_sym, rhs_sym)])
    free, along_p, along_d = [], [], []
    for mass, force, top in zip(mass_blocks, force_blocks, top_jacobians, strict=True):
        solved = element_solve(mass, ca.horzcat(force, select.T, top.T))
        free.append(solved[:, 0] if columns == 1 else solved[:, :columns])
        along_p.append(solved[:, columns : columns + 3])
        along_d.append(solved[:, columns + 3 : columns + 6])

    # Bond j (index j-1 here) couples element j-1 (block -D) and element j (block P).
    diag, upper, lower, rhs = [], [], [], []
    for j in range(1, count + 1):
        below = j - 1
        block = top_jacobians[below] @ along_d[below]
        residual = bond_rhs[j - 1] + top_jacobians[below] @ free[below]
        if j < count:
            block = block + select @ along_p[j]
            residual = residual - select @ free[j]
            upper.append(-select @ along_d[j])
            lower.append(-top_jacobians[j] @ along_p[j])
        diag.append(block)
        rhs.append(residual)

    inverses, reduced = [inverse_3x3(diag[0])], [rhs[0]]
    for j in range(1, count):
        factor = lower[j - 1] @ inverses[j - 1]
        inverses.append(inverse_3x3(diag[j] - factor @ upper[j - 1]))
        reduced.append(rhs[j] - factor @ reduced[j - 1])
    forces = [None] * count
    forces[-1] = inverses[-1] @ reduced[-1]
    for j in reversed(range(count - 1)):
        forces[j] = inverses[j] @ (reduced[j] - upper[j] @ forces[j + 1])

    accelerations = []
    for i in range(count):
        acc = free[i] - along_d[i] @ forces[i]
        if i > 0:
            acc = acc + along_p[i] @ forces[i - 1]
        accelerations.append(acc)
    return accelerations, forces


def sparse_kkt_solve(
    mass: ca.MX, force: ca.MX, bond_jacobian: ca.MX, bond_rhs: ca.MX, solver: str = "csparse"
) -> tuple[ca.MX, ca.MX]:
    """Accelerations and bond forces from the assembled KKT system, by a general sparse solver.

    Solves ``[[M, -C^T], [C, 0]] [q''; lambda] = [f; b]``.

    Returns
    -------
    accelerations, bond_forces : MX
    """
    size = mass.shape[0]
    kkt = ca.blockcat(
        [
            [mass, -bond_jacobian.T],
            [bond_jacobian, ca.MX(bond_jacobian.shape[0], bond_jacobian.shape[0])],
        ]
    )
    solution = ca.solve(kkt, ca.vertcat(force, bond_rhs), solver)
    return solution[:size], solution[size:]
