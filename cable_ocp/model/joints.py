"""Terms of the bonds and joints shared by every right-hand side (flat, structured, elastic).

A bond is imposed at acceleration level with Baumgarte's stabilisation; a joint between two
elements carries the bending spring and its Rayleigh damping (CONVENTIONS.md §4).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import casadi as ca


def baumgarte(quadratic, rate, residual, spec):
    """Right-hand side of a bond at acceleration level: ``Phi'' + 2 alpha Phi' + beta^2 Phi = 0``.

    ``quadratic`` is the part of ``Phi''`` without the accelerations, ``rate`` is ``Phi'`` and
    ``residual`` is ``Phi`` (m/s^2, m/s, m); the gains come from ``spec`` (1/s).
    """
    alpha, beta = spec.baumgarte_alpha, spec.baumgarte_beta
    return quadratic - 2 * alpha * rate - beta**2 * residual


def bending_energies(axis_below, axis_above, rate_below, rate_above, spec):
    """Bending potential (J) and Rayleigh dissipation (W) of the joint between two elements.

    ``k (1 - e_below . e_above)`` with ``k = EI / Delta``, and ``1/2 c k |e'_above - e'_below|^2``
    with the Rayleigh time constant ``c`` (s).
    """
    bending = spec.bending_stiffness / spec.segment_length
    potential = bending * (1 - ca.dot(axis_below, axis_above))
    relative_rate = rate_above - rate_below
    dissipation = 0.5 * spec.bending_damping * bending * ca.dot(relative_rate, relative_rate)
    return potential, dissipation


def top_bond_kernel(model) -> ca.Function:
    """Right-hand side of the top bond from its quadratic part, rate and residual (Baumgarte).

    ``(quadratic, rate, residual, p)``: a kernel of the structured loops, whose gains are the
    parametric ``model``'s.
    """
    quadratic, rate, residual = (ca.SX.sym(name, 3) for name in ("quadratic", "rate", "residual"))
    return ca.Function(
        "top_bond",
        [quadratic, rate, residual, model.p],
        [baumgarte(quadratic, rate, residual, model.spec)],
    )


@dataclass(frozen=True)
class Kernels:
    """The small Functions the structured loops call, and what they take as ``p``.

    ``parameters`` maps the graph's ``p`` (MX) to the ``p`` the kernels take: the identity for
    the kernels of the model itself (:func:`kernels_of`); one set of kernels built and compiled
    on another structure of another ``n`` serves every ``n`` when it maps the segment length
    onto its own (:mod:`cable_ocp.model.payout`).
    """

    joint: ca.Function
    element: ca.Function
    element_end: ca.Function
    bond: ca.Function
    top_bond: ca.Function
    forward: ca.Function
    backward: ca.Function
    accelerations: ca.Function
    inverse: ca.Function
    segment_length: ca.Function
    parameters: Callable[[ca.MX], ca.MX] = lambda p: p

    def map(self, name: str, count: int) -> Callable:
        """Kernel ``name`` over ``count`` columns (CasADi's ``map``)."""
        return getattr(self, name).map(count)

    def mapaccum(self, name: str, count: int) -> Callable:
        """Kernel ``name`` accumulated over ``count`` columns (CasADi's ``mapaccum``)."""
        return getattr(self, name).mapaccum(count)


def chain_outputs(q, qd, upper_points, upper_rates, residual, rate, bond_forces, qdd) -> list:
    """The flat model's outputs in the order of :data:`~cable_ocp.model.layout.OUTPUT_NAMES`.

    Joints ``A_0 .. A_{n+1}`` and their velocities (the top from the top element's upper point),
    the bond residuals and rates, the bond forces, their norms (the tensions) and ``q''``.
    """
    return [
        ca.horzcat(*[qi[:3] for qi in q], upper_points[-1]),
        ca.horzcat(*[qdi[:3] for qdi in qd], upper_rates[-1]),
        ca.vertcat(*residual),
        ca.vertcat(*rate),
        ca.horzcat(*bond_forces),
        ca.vertcat(*[ca.norm_2(f) for f in bond_forces]),
        qdd,
    ]
