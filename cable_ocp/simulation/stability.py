"""The RK4 step limit of a linearisation: eigenvalues of the Jacobian against RK4's region.

Used by the stability study (:mod:`cable_ocp.studies.stability`) and by model correction, which
runs the full model at a coarser step while it stays well inside this limit
(:func:`cable_ocp.control.verification.correction_step`).
"""

from __future__ import annotations

import math

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


# Share of the linearised RK4 limit that a step chosen from it may take. The stability study's
# runs at 0.53 and 0.68 of the limit (n = 15 at h = 0.2 s, n = 100 at 0.025 s) kept the end within
# 2e-6 m and 1e-7 m of runs at a quarter of their step (notebooks/studies/bench.md).
STABLE_SHARE = 0.7
# States along a run at which the limit is taken (evenly spaced in time, the start included).
LIMIT_PROBES = 24


def limit_along_run(
    model: CableModel,
    x0: np.ndarray,
    drive,
    duration: float,
    compiled: bool = False,
) -> tuple[float, float]:
    """The smallest linearised RK4 limit (s) over a run of ``drive``, and when it is reached (s).

    Drag stiffens the model as the cable moves through the water (its linearisation grows with
    the relative speed), so the limit at rest says too little: the run is integrated at a share
    of the limit at rest (halved while it blows up) and :func:`linearised_step` is taken at
    :data:`LIMIT_PROBES` of its states, evenly spaced in time.

    Parameters
    ----------
    model : CableModel
    x0 : array (state_size,)
        The run's start.
    drive : Drive
        Its inputs (e.g. the locked winch).
    duration : float, s
    compiled : bool
        Run and difference the compiled model (5-DOF structures).

    Raises
    ------
    cable_ocp.simulation.integrate.SimulationError
        When the run blows up even at a sixteenth of the limit at rest.
    """
    from cable_ocp.model import structured
    from cable_ocp.simulation.integrate import SimulationError, integrate

    rhs = None
    if compiled and structured.supports(model):
        rhs = structured.compiled_structured(model, "rhs")
    rest = linearised_step(model, x0, drive.inputs(np.zeros(1))[:, 0], rhs=rhs)
    probe = STABLE_SHARE * rest / 2
    for attempt in range(4):
        count = max(LIMIT_PROBES, math.ceil(duration / probe))
        count = LIMIT_PROBES * math.ceil(count / LIMIT_PROBES)
        try:
            run = integrate(
                model, x0, drive, duration, duration / count,
                output_every=count // LIMIT_PROBES, tolerance=math.inf, compiled=compiled,
            )  # fmt: skip
            break
        except SimulationError:
            if attempt == 3:
                raise
            probe /= 2
    limits = [
        linearised_step(model, state, inputs, rhs=rhs)
        for state, inputs in zip(run.states, run.inputs, strict=True)
    ]
    worst = int(np.argmin(limits))
    return float(limits[worst]), float(run.time[worst])
