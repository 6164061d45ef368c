"""One rigid element of a rope that stretches: the rfe element with the line's axial strain ``s``.

The elastic rope (CONVENTIONS.md §4, "Axial elasticity") keeps the paper's rigid elements and adds
one generalised coordinate shared by all of them: the uniform axial strain ``s`` of the line. An
element of rest length ``l0`` has the length ``l = (1 + s) l0``; a material point at the rest
distance ``xi0`` from ``A_i`` sits at ``A_i + (1 + s) xi0 e``. The element's local coordinates are
``q = (x, y, z, psi, theta, s)``; its mass is ``mu l0`` whatever the stretch.

With ``sigma = 1 + s``, ``mu' = mu / sigma`` (mass per stretched metre), ``w = s' / sigma``, the
velocity of the point at the stretched distance ``xi`` is ``v + xi (e' + w e)``, and the kinetic
energy of the element and its entrained water, integrated along the element by hand, is the rigid
element's closed form (:func:`cable_ocp.model.rfe.closed_form_kinetic_energy`) with ``mu'`` in
place of ``mu``, plus the stretching terms::

    1/2 (mu' + a_t) (l^2 w v.e + l^3 w^2 / 3)

Weight less buoyancy is carried per rest metre; drag per stretched metre, at Gauss points that
move with the material. The mass matrix, the velocity terms and every generalised force (on the
strain too) follow by automatic differentiation, so the energy of the rope and the water is
conserved without dissipation (tests/test_axial.py).
"""

from __future__ import annotations

import casadi as ca

from cable_ocp.model.current import current_at
from cable_ocp.model.hydro import drag_force_density, gauss_points
from cable_ocp.model.kinematics import POSITION, axis_direction
from cable_ocp.model.rfe import ElementProperties, added_mass_per_length, element_function_pair

STRAIN = 5  # index of the strain in an elastic element's local coordinates


def elastic_kinetic_energy(
    q: ca.SX, qd: ca.SX, rest_length: ca.SX, props: ElementProperties
) -> ca.SX:
    """Kinetic energy (J) of a stretching 5-DOF element with its added mass (module docstring)."""
    normal_added, axial_added = added_mass_per_length(props)
    stretch = 1 + q[STRAIN]
    length = stretch * rest_length
    mu = props.mass_per_length / stretch
    normal_mass = mu + normal_added
    section = props.mass_per_length * rest_length * props.diameter**2 / 16
    axis = axis_direction(q[3], q[4])
    axis_rate = ca.jtimes(axis, q, qd)
    velocity = qd[POSITION]
    strain_rate = qd[STRAIN] / stretch
    translation = (
        normal_mass * ca.dot(velocity, velocity)
        + (axial_added - normal_added) * ca.dot(velocity, axis) ** 2
    )
    stretching = (mu + axial_added) * (
        length**2 * strain_rate * ca.dot(velocity, axis) + length**3 * strain_rate**2 / 3
    )
    return (
        0.5 * length * translation
        + 0.5 * length**2 * normal_mass * ca.dot(velocity, axis_rate)
        + 0.5 * (length**3 * normal_mass / 3 + section) * ca.dot(axis_rate, axis_rate)
        + section * (qd[3] * ca.sin(q[4])) ** 2
        + 0.5 * stretching
    )


def elastic_element_functions(
    props: ElementProperties, parameters: ca.SX | None = None
) -> tuple[ca.Function, ca.Function]:
    """The per-element terms of a stretching element, as SX Functions inlined for every element.

    Inputs ``q``, ``qd`` (6: the element's five coordinates and the line's strain), ``length``
    (the rest length ``l0``, m) and the parameter vector ``p`` when ``props`` holds its symbols.
    Outputs:

    - ``mass_matrix`` (6 x 6): rigid, stretching and added mass;
    - ``force`` (6): ``-h``, weight less buoyancy and drag, on the coordinates and the strain;
    - ``axis``, ``axis_rate`` (3): ``e`` and ``e'``;
    - ``top_point`` (3): ``A_{i+1} = A_i + (1 + s) l0 e``;
    - ``top_jacobian`` (3 x 6): its Jacobian;
    - ``top_quadratic`` (3): its second derivative at zero accelerations (rest length fixed).

    The second Function gives the element's kinetic energy plus its gravity potential (J).
    """
    if props.torsion:
        raise ValueError("an elastic rope needs 5-DOF elements (model.torsion = false)")
    q = ca.SX.sym("q", 6)
    qd = ca.SX.sym("qd", 6)
    rest_length = ca.SX.sym("length")
    kinetic = elastic_kinetic_energy(q, qd, rest_length, props)
    momentum = ca.gradient(kinetic, qd)
    mass_matrix = ca.jacobian(momentum, qd)
    velocity_terms = ca.jtimes(momentum, q, qd) - ca.gradient(kinetic, q)

    stretch = 1 + q[STRAIN]
    axis = axis_direction(q[3], q[4])
    centre_height = q[2] + 0.5 * stretch * rest_length * axis[2]
    potential = props.submerged_weight_per_length * rest_length * centre_height
    force = -velocity_terms - ca.gradient(potential, q)

    hydro = props.hydro
    if hydro is not None and hydro.has_drag:
        for xi, weight in gauss_points(rest_length, hydro.quadrature_points):
            point = q[POSITION] + stretch * xi * axis
            jac = ca.jacobian(point, q)
            current = current_at(hydro, point[2])
            drag = drag_force_density(jac @ qd, axis, hydro, current)
            force = force + stretch * weight * jac.T @ drag

    top_point = q[POSITION] + stretch * rest_length * axis
    top_jacobian = ca.jacobian(top_point, q)
    top_quadratic = ca.jtimes(top_jacobian @ qd, q, qd)
    terms = {
        "mass_matrix": ca.densify(mass_matrix),
        "force": force,
        "axis": axis,
        "axis_rate": ca.jtimes(axis, q, qd),
        "top_point": top_point,
        "top_jacobian": top_jacobian,
        "top_quadratic": top_quadratic,
    }
    energy = kinetic + potential
    return element_function_pair("elastic_element", [q, qd, rest_length], parameters, terms, energy)
