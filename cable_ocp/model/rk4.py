"""Classical RK4 steps of the model: one definition for every integrator and library."""

from __future__ import annotations

from collections.abc import Callable

import casadi as ca

from cable_ocp.model.layout import INPUT_SIZE
from cable_ocp.model.parametric import ParametricModel


def parametric_rk4_step(parametric: ParametricModel, rhs: ca.Function | None = None) -> ca.Function:
    """One RK4 step of a structure: ``(x, stage_inputs, p, h) -> x_next``, ``h`` in s.

    With the parametric right-hand side the step is one SX Function; with another ``rhs`` of
    ``(x, u, p)`` (the structured one, a compiled one) it is an MX Function calling it four times.
    """
    kind = ca.SX if rhs is None else ca.MX
    rhs = parametric.rhs if rhs is None else rhs
    x = kind.sym("x", parametric.state_size)
    stages = kind.sym("stage_inputs", INPUT_SIZE, 3)
    p, h = kind.sym("p", parametric.p.numel()), kind.sym("h")
    x_next = rk4(lambda state, u: rhs(state, u, p), x, stages, h)
    return ca.Function(
        "rk4_step", [x, stages, p, h], [x_next], ["x", "stage_inputs", "p", "h"], ["x_next"]
    )


def rk4(rhs: Callable, x, stages, step):
    """``x`` after one RK4 step of ``step`` (s) of ``x' = rhs(x, u)``.

    ``stages`` holds ``u`` at ``t``, ``t + h/2`` and ``t + h`` in its three columns.
    """
    k1 = rhs(x, stages[:, 0])
    k2 = rhs(x + step / 2 * k1, stages[:, 1])
    k3 = rhs(x + step / 2 * k2, stages[:, 1])
    k4 = rhs(x + step * k3, stages[:, 2])
    return x + step / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
