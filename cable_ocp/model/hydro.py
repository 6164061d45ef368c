"""Morison hydrodynamics of one element: drag by Gauss quadrature and added mass (paper §3).

Drag per unit length (CONVENTIONS.md §4, the MoorDyn convention)::

    f = -1/2 rho_w d C_dn |V_n| V_n - 1/2 rho_w pi d C_dt |V_t| V_t

with ``V = v - v_current`` split into its part along the element axis (``V_t``) and across it
(``V_n``); ``v_current`` is the current at the point's depth (:mod:`cable_ocp.model.current`).
Added mass acts on the acceleration of each point of the axis with the coefficient ``C_a`` across
and ``C_at`` along the axis, through the kinetic energy of the entrained water
(:func:`cable_ocp.model.rfe.added_mass_energy`); ``C_at = C_a`` is the paper's isotropic eq. 28-32.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from cable_ocp.model.parameters import is_on

# Regularises |V| as sqrt(V.V + eps^2) so that the right-hand side stays differentiable at rest.
SMOOTH_SPEED = 1e-4  # m/s


@dataclass(frozen=True)
class HydroCoefficients:
    """Water and coefficients that the hydrodynamic forces need.

    Attributes
    ----------
    water_density : float, kg/m^3
        Of the water around the rope.
    diameter : float, m
        The rope's, across which the drag acts.
    area : float, m^2
        Cross-section area used for the added mass.
    drag_normal, drag_axial : float
        C_dn and C_dt (0 switches the term off).
    added_mass_normal, added_mass_axial : float
        C_a and C_at (0 switches the term off).
    current : tuple of 3 float, m/s
        Uniform current velocity (zero when a profile is given).
    quadrature_points : int
        Gauss-Legendre points per element for the drag.
    current_z : tuple of float, m
        Heights of the current profile's rows, from the surface down (empty: uniform current).
    current_u, current_v : tuple of float, m/s
        The profile's current along x and y at those heights.
    """

    water_density: float
    diameter: float
    area: float
    drag_normal: float
    drag_axial: float
    added_mass_normal: float
    added_mass_axial: float
    current: tuple[float, float, float]
    quadrature_points: int
    current_z: tuple[float, ...] = ()
    current_u: tuple[float, ...] = ()
    current_v: tuple[float, ...] = ()

    @property
    def has_drag(self) -> bool:
        """Whether any drag coefficient is non-zero."""
        return is_on(self.water_density) and (is_on(self.drag_normal) or is_on(self.drag_axial))

    @property
    def has_added_mass(self) -> bool:
        """Whether any added-mass coefficient is non-zero."""
        return is_on(self.water_density) and (
            is_on(self.added_mass_normal) or is_on(self.added_mass_axial)
        )


def gauss_points(length: ca.SX, count: int) -> list[tuple[ca.SX, ca.SX]]:
    """Gauss-Legendre abscissae and weights on [0, length].

    Returns
    -------
    list of (xi, weight), (m, m)
    """
    nodes, weights = np.polynomial.legendre.leggauss(count)
    return [
        (0.5 * length * (1.0 + x), 0.5 * length * w) for x, w in zip(nodes, weights, strict=True)
    ]


def smooth_norm(v: ca.SX) -> ca.SX:
    """Differentiable approximation of |v| (m/s)."""
    return ca.sqrt(ca.dot(v, v) + SMOOTH_SPEED**2)


def drag_force_density(
    velocity: ca.SX, axis: ca.SX, hydro: HydroCoefficients, current: ca.SX
) -> ca.SX:
    """Morison drag per unit length (N/m) on a point of the axis.

    ``velocity`` and ``current`` (m/s) are the point's and the water's there
    (:func:`cable_ocp.model.current.current_at`); ``axis`` the element's unit axis.
    """
    relative = velocity - current
    axial = ca.dot(relative, axis) * axis
    normal = relative - axial
    half_rho_d = 0.5 * hydro.water_density * hydro.diameter
    force = ca.DM.zeros(3)
    if is_on(hydro.drag_normal):
        force = force - half_rho_d * hydro.drag_normal * smooth_norm(normal) * normal
    if is_on(hydro.drag_axial):
        force = force - half_rho_d * np.pi * hydro.drag_axial * smooth_norm(axial) * axial
    return force


def added_mass_tensor(axis: ca.SX, hydro: HydroCoefficients) -> ca.SX:
    """Added mass per unit length (kg/m, 3x3) of a point of an element with unit ``axis``."""
    along = axis @ axis.T
    rho_a = hydro.water_density * hydro.area
    return rho_a * (
        hydro.added_mass_normal * (ca.DM.eye(3) - along) + hydro.added_mass_axial * along
    )
