"""Equations of one rigid finite element (rfe) from its energies (paper §2, CONVENTIONS.md §4).

An element of length ``l`` spans from ``A_i`` (its coordinates ``x, y, z``) along the axis ``e`` to
``A_{i+1} = A_i + l e``. The kinetic energy is that of a uniform solid cylinder, which is the
paper's ``1/2 tr(B' H B'^T)`` (eq. 4-5) written with the rotation matrix; the mass matrix and the
velocity terms follow from it by automatic differentiation (eq. 6).
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from cable_ocp.model.current import current_at
from cable_ocp.model.hydro import (
    HydroCoefficients,
    added_mass_tensor,
    drag_force_density,
    gauss_points,
)
from cable_ocp.model.kinematics import POSITION, axis_direction, rotation_matrix


@dataclass(frozen=True)
class ElementProperties:
    """Material data shared by every element of a cable.

    Attributes
    ----------
    mass_per_length : float, kg/m
        The rope's own mass per metre (without added mass).
    diameter : float, m
        Its outer diameter.
    submerged_weight_per_length : float, N/m
        Weight less buoyancy per unit length (eq. 13, 23-24).
    torsion : bool
        6-DOF elements (with the twist angle) when true.
    hydro : HydroCoefficients or None
        None in air.
    """

    mass_per_length: float
    diameter: float
    submerged_weight_per_length: float
    torsion: bool
    hydro: HydroCoefficients | None

    @property
    def dofs(self) -> int:
        """Generalised coordinates per element (5 or 6)."""
        return 6 if self.torsion else 5


def element_rotation(q: ca.SX, torsion: bool) -> ca.SX:
    """Rotation matrix of an element from its generalised coordinates."""
    return rotation_matrix(q[3], q[4], q[5] if torsion else 0.0)


def kinetic_energy(q: ca.SX, qd: ca.SX, length: ca.SX, props: ElementProperties) -> ca.SX:
    """Kinetic energy (J) of a uniform cylinder element, without added mass.

    ``T = 1/2 m |r'|^2 + m r'.(R' c) + 1/2 tr(R' J R'^T)`` with ``c = (l/2, 0, 0)`` and
    ``J = diag(m l^2/3, m d^2/16, m d^2/16)``: the trace form of eq. 4 with ``H`` of eq. 5.
    """
    mass = props.mass_per_length * length
    rotation = element_rotation(q, props.torsion)
    rotation_rate = ca.jtimes(rotation, q, qd)
    velocity = qd[POSITION]
    centre = ca.vertcat(length / 2, 0, 0)
    transverse = mass * props.diameter**2 / 16
    second_moment = ca.diag(ca.vertcat(mass * length**2 / 3, transverse, transverse))
    return (
        0.5 * mass * ca.dot(velocity, velocity)
        + mass * ca.dot(velocity, rotation_rate @ centre)
        + 0.5 * ca.trace(rotation_rate @ second_moment @ rotation_rate.T)
    )


def axis_point_jacobian(q: ca.SX, xi: ca.SX) -> ca.SX:
    """Jacobian (3 x dofs) of the axis point at distance ``xi`` (m) from A_i w.r.t. q."""
    point = q[POSITION] + xi * axis_direction(q[3], q[4])
    return ca.jacobian(point, q)


def added_mass_energy(
    q: ca.SX, qd: ca.SX, length: ca.SX, axis: ca.SX, hydro: HydroCoefficients
) -> ca.SX:
    """Kinetic energy of the water entrained by the element (J).

    ``1/2 int v^T N v dxi`` with the added-mass tensor ``N`` of :func:`added_mass_tensor`; the
    integrand is quadratic in ``xi``, so two Gauss points are exact. With ``C_at = C_a`` its
    Lagrange terms are the paper's eq. 31-32; otherwise they add the terms from ``N`` turning with
    the element, which keep the energy of the cable and the water conserved.
    """
    tensor = added_mass_tensor(axis, hydro)
    energy = 0
    for xi, weight in gauss_points(length, 2):
        velocity = axis_point_jacobian(q, xi) @ qd
        energy = energy + 0.5 * weight * velocity.T @ tensor @ velocity
    return energy


def closed_form_kinetic_energy(
    q: ca.SX, qd: ca.SX, length: ca.SX, props: ElementProperties
) -> ca.SX:
    """Kinetic energy (J) of a 5-DOF element with its added mass, in closed form.

    The same energy as :func:`kinetic_energy` plus :func:`added_mass_energy`, integrated along
    the element by hand, so that automatic differentiation of it gives a far shorter expression
    (0.4 times the instructions of the element's equations). With ``v`` the velocity of ``A_i``,
    ``e`` the axis, ``a_n = rho_w A C_a``, ``a_t = rho_w A C_at``, ``m_n = mu + a_n`` and the
    section's second moment ``J_s = mu l d^2 / 16``::

        T = 1/2 l (m_n |v|^2 + (a_t - a_n) (v.e)^2) + 1/2 l^2 m_n v.e'
            + 1/2 (l^3 m_n / 3 + J_s) |e'|^2 + J_s (psi' sin theta)^2

    The last term is the section spinning about the axis, ``J_s (omega.e)^2``; ``e'`` is normal
    to ``e``, so the added mass acts on it with ``a_n`` alone.
    """
    if props.torsion:
        raise ValueError("the closed-form kinetic energy is for 5-DOF elements (torsion off)")
    normal_added, axial_added = added_mass_per_length(props)
    mu = props.mass_per_length
    normal_mass = mu + normal_added
    section = mu * length * props.diameter**2 / 16
    axis = axis_direction(q[3], q[4])
    axis_rate = ca.jtimes(axis, q, qd)
    velocity = qd[POSITION]
    translation = (
        normal_mass * ca.dot(velocity, velocity)
        + (axial_added - normal_added) * ca.dot(velocity, axis) ** 2
    )
    return (
        0.5 * length * translation
        + 0.5 * length**2 * normal_mass * ca.dot(velocity, axis_rate)
        + 0.5 * (length**3 * normal_mass / 3 + section) * ca.dot(axis_rate, axis_rate)
        + section * (qd[3] * ca.sin(q[4])) ** 2
    )


def added_mass_per_length(props: ElementProperties) -> tuple[float, float]:
    """Added mass per unit length across and along the axis, ``rho_w A C_a`` and ``C_at`` (kg/m).

    Both 0 in air or with the added mass switched off.
    """
    hydro = props.hydro
    if hydro is None or not hydro.has_added_mass:
        return 0.0, 0.0
    water_per_length = hydro.water_density * hydro.area
    return water_per_length * hydro.added_mass_normal, water_per_length * hydro.added_mass_axial


def element_functions(
    props: ElementProperties, parameters: ca.SX | None = None
) -> tuple[ca.Function, ca.Function]:
    """Build the per-element terms as SX Functions, to be inlined for every element.

    Inputs ``q``, ``qd`` (dofs), ``length`` (m) and, when ``props`` holds symbols of a parameter
    vector (:func:`cable_ocp.model.parameters.symbolic_spec`), that vector ``parameters`` as ``p``.
    Outputs:

    - ``mass_matrix`` (dofs x dofs, kg, kg m, kg m^2): rigid plus added mass, from the kinetic
      energy of both (CONVENTIONS.md §4);
    - ``force`` (dofs): generalised force without bonds and springs: ``-h`` (eq. 6, 32), weight
      less buoyancy (eq. 14, 24 corrected) and Morison drag (eq. 26);
    - ``axis``, ``axis_rate`` (3): ``e`` and its rate;
    - ``axis_quadratic`` (3): ``d/dt(e')`` at zero angular acceleration;
    - ``top_jacobian`` (3 x dofs): Jacobian of ``A_{i+1} = A_i + l e``;

    The second Function gives the element's energy (J): kinetic (with added mass) plus the
    gravity/buoyancy potential.
    """
    dofs = props.dofs
    q = ca.SX.sym("q", dofs)
    qd = ca.SX.sym("qd", dofs)
    length = ca.SX.sym("length")

    axis = axis_direction(q[3], q[4])
    hydro = props.hydro
    if props.torsion:
        kinetic = kinetic_energy(q, qd, length, props)
        if hydro is not None and hydro.has_added_mass:
            kinetic = kinetic + added_mass_energy(q, qd, length, axis, hydro)
    else:
        kinetic = closed_form_kinetic_energy(q, qd, length, props)
    momentum = ca.gradient(kinetic, qd)
    mass_matrix = ca.jacobian(momentum, qd)
    velocity_terms = ca.jtimes(momentum, q, qd) - ca.gradient(kinetic, q)

    centre_height = q[2] + 0.5 * length * axis[2]
    potential = props.submerged_weight_per_length * length * centre_height
    force = -velocity_terms - ca.gradient(potential, q)

    if hydro is not None and hydro.has_drag:
        for xi, weight in gauss_points(length, hydro.quadrature_points):
            jac = axis_point_jacobian(q, xi)
            current = current_at(hydro, q[2] + xi * axis[2])
            force = force + weight * jac.T @ drag_force_density(jac @ qd, axis, hydro, current)

    axis_rate = ca.jtimes(axis, q, qd)
    axis_quadratic = ca.jtimes(axis_rate, q, qd)
    top_jacobian = ca.jacobian(q[POSITION] + length * axis, q)
    terms = {
        "mass_matrix": ca.densify(mass_matrix),
        "force": force,
        "axis": axis,
        "axis_rate": axis_rate,
        "axis_quadratic": axis_quadratic,
        "top_jacobian": top_jacobian,
    }
    return element_function_pair("element", [q, qd, length], parameters, terms, kinetic + potential)


def element_function_pair(
    name: str,
    inputs: list[ca.SX],
    parameters: ca.SX | None,
    terms: dict[str, ca.SX],
    energy: ca.SX,
) -> tuple[ca.Function, ca.Function]:
    """An element's terms and its energy as two Functions of the same named inputs.

    Parameters
    ----------
    name : str
        The terms' Function; the energy's is ``<name>_energy``.
    inputs : list of SX
        ``q``, ``qd`` and ``length`` (m), named so.
    parameters : SX or None
        The parameter vector the terms hold symbols of, the last input ``p``; none if None.
    terms : dict of str to SX
        The outputs of the first Function, by name, in order.
    energy : SX, J
        The output ``energy`` of the second.
    """
    names = ["q", "qd", "length"]
    if parameters is not None:
        inputs, names = [*inputs, parameters], [*names, "p"]
    return (
        ca.Function(name, inputs, list(terms.values()), names, list(terms)),
        ca.Function(f"{name}_energy", inputs, [energy], names, ["energy"]),
    )
