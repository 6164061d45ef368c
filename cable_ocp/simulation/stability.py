"""The RK4 step limit of a linearisation: eigenvalues of the Jacobian against RK4's region.

Used by the stability study (:mod:`cable_ocp.studies.stability`) and by model correction, which
runs the full model at a coarser step while it stays well inside this limit
(:func:`cable_ocp.control.verification.correction_step`).
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from cable_ocp.model.cable import CableModel

# |R(h lambda)| of RK4 may exceed its bound by this much (rounding) and count as stable.
GROWTH_SLACK = 1e-6


def rk4_growth(z: np.ndarray) -> np.ndarray:
    """``|R(z)|`` of classical RK4, ``R(z) = 1 + z + z^2/2 + z^3/6 + z^4/24``."""
    return np.abs(1 + z + z**2 / 2 + z**3 / 6 + z**4 / 24)


def linearised_step(
    model: CableModel,
    x: np.ndarray,
    u: np.ndarray,
    relative: float = 1e-7,
    rhs: ca.Function | None = None,
) -> float:
    """Largest RK4 step (s) stable for the linearisation of the model at ``(x, u)``.

    The Jacobian of the right-hand side is taken by forward differences (one batched call;
    building it symbolically takes minutes at n = 100). For each eigenvalue ``lambda`` the largest
    ``h`` with ``|R(h lambda)| <= max(1, |exp(h lambda)|)`` is found by bisection, and the smallest
    is returned: RK4 may grow no faster than the exact solution, so the slow modes that the
    differences leave slightly in the right half-plane do not count as unstable.

    Parameters
    ----------
    model : CableModel
    x : array (state_size,)
    u : array (15,)
    relative : float
        Difference step, relative to ``max(1, |x_j|)``.
    rhs : casadi.Function, optional
        ``(x, u) -> x'`` to difference, e.g. a compiled one; the model's own by default.
    """
    size = model.state_size
    steps = relative * np.maximum(1.0, np.abs(x))
    probes = np.hstack([x[:, None], x[:, None] + np.diag(steps)])
    rhs = model.rhs if rhs is None else rhs
    values = np.array(rhs.map(size + 1)(probes, np.tile(u[:, None], (1, size + 1))))
    eigenvalues = np.linalg.eigvals((values[:, 1:] - values[:, :1]) / steps)
    eigenvalues = eigenvalues[np.abs(eigenvalues) > 0]
    # The RK4 region lies inside |z| < 3, so h = 3 / |lambda| is unstable for every lambda.
    low, high = np.zeros(eigenvalues.size), 3.0 / np.abs(eigenvalues)
    for _ in range(60):
        middle = (low + high) / 2
        z = middle * eigenvalues
        stable = rk4_growth(z) <= np.maximum(1.0, np.exp(z.real)) + GROWTH_SLACK
        low, high = np.where(stable, middle, low), np.where(stable, high, middle)
    return float(low.min())
