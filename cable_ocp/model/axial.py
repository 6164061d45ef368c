"""The equations of a rope that stretches: the rigid chain plus the line's uniform axial strain.

The paper's rope is inextensible: its bonds remove the axial modes so that RK4 can take large
steps. Where a scene's line and payload form a spring and a mass whose period reaches the wave
band (CONVENTIONS.md §4, "Axial elasticity"), the model adds one generalised coordinate, the
uniform strain ``s`` of the whole line, a Ritz approximation of its first axial mode: every
element's length is ``(1 + s)`` times its rest length, the bonds hold as before, and the strain
carries the elastic energy ``1/2 EA L0 s^2`` (``L0`` the rest length of the line out) and a
structural damping ``c s'`` with ``c = 2 zeta sqrt(EA L0 m_s)``: ``zeta`` is the damping ratio of
the mode and ``m_s`` its generalised mass (below). Its period is
``2 pi sqrt((M + A33 + m L / 3) / (EA / L))`` for a hanging line, its static stretch
``(W L + w' L^2 / 2) / EA``: the elastic catenary's (eq. 34) for the end. The higher axial
modes (periods shorter by 3x or more) are left out, so the step stays that of the rigid chain.

The state is ``[q_0 .. q_n, s, q'_0 .. q'_n, s']``. The mass matrix is the rigid chain's block
diagonal bordered by the strain; the elimination keeps the O(n) block Thomas solve
(:func:`cable_ocp.model.kkt.thomas_solve`) and solves two right-hand sides with it: the chain's
own forces (``A``), and its response to a unit strain acceleration (``B``: the forces ``-b_i``
of the bordered mass matrix and the bond terms ``d_i = d A_{i+1} / ds``). Then
``q'' = q''_A + s'' q''_B``, ``lambda = lambda_A + s'' lambda_B`` and the strain's own equation
gives ``s''``::

    m_s s'' = f_s - sum_i d_i . lambda_A,i - sum_i b_i . q''_A,i
    m_s = m_ss + sum_i d_i . lambda_B,i + sum_i b_i . q''_B,i
"""

from __future__ import annotations

from types import SimpleNamespace

import casadi as ca

from cable_ocp.model.axial_element import elastic_element_functions
from cable_ocp.model.joints import baumgarte, chain_outputs
from cable_ocp.model.kinematics import POSITION
from cable_ocp.model.kkt import thomas_solve
from cable_ocp.model.layout import INPUTS, top_inputs


def elastic_graph(model) -> SimpleNamespace:
    """The SX expressions of an elastic model's flat Functions (as the rigid ``_graph``).

    Parameters
    ----------
    model : ParametricModel
        A model whose spec has an axial stiffness (``model.axial``); its layout, springs and end
        loads are used as they are.
    """
    spec, p = model.spec, model.p
    element, element_energy = elastic_element_functions(spec.element, p)
    dofs = model.dofs
    q, qd = model.coordinates(model.x)
    strain, strain_rate = model.strain(model.x)
    u = model.u
    top, top_velocity, top_acceleration, top_length, top_length_rate, top_length_acc = top_inputs(u)
    rest = model.element_lengths(top_length)
    local = [ca.vertcat(qi, strain) for qi in q]
    local_rates = [ca.vertcat(qdi, strain_rate) for qdi in qd]
    terms = [element(*args, p) for args in zip(local, local_rates, rest, strict=True)]

    mass = [t[0][:dofs, :dofs] for t in terms]
    coupling = [t[0][:dofs, dofs] for t in terms]
    strain_mass = sum(t[0][dofs, dofs] for t in terms)
    axes = [t[2] for t in terms]
    axis_rates = [t[3] for t in terms]
    upper_points = [t[4] for t in terms]
    top_jacobians = [t[5][:, :dofs] for t in terms]
    strain_jacobians = [t[5][:, dofs] for t in terms]

    q_all, qd_all = ca.vertcat(*q), ca.vertcat(*qd)
    potential, dissipation = model.spring_energies(q, qd, axes, axis_rates)
    chain_force = -ca.gradient(potential, q_all) - ca.gradient(dissipation, qd_all)
    forces = [t[1][:dofs] + chain_force[i * dofs : (i + 1) * dofs] for i, t in enumerate(terms)]
    mass[0], forces[0] = model.end_loads(mass[0], forces[0], q[0], qd[0], u[INPUTS.end_force])

    stretch = 1 + strain
    line_length = sum(rest)
    stiffness = spec.axial_stiffness * line_length
    upper_rates = [t[5] @ qdl for t, qdl in zip(terms, local_rates, strict=True)]
    upper_rates[-1] = upper_rates[-1] + top_length_rate * stretch * axes[-1]
    quadratic = [t[6] for t in terms]
    quadratic[-1] = (
        quadratic[-1]
        + top_length_acc * stretch * axes[-1]
        + 2 * top_length_rate * (strain_rate * axes[-1] + stretch * axis_rates[-1])
        - top_acceleration
    )
    lower_points = [qi[POSITION] for qi in q[1:]] + [top]
    lower_rates = [qdi[POSITION] for qdi in qd[1:]] + [top_velocity]
    residual = [lo - up for lo, up in zip(lower_points, upper_points, strict=True)]
    rate = [lo - up for lo, up in zip(lower_rates, upper_rates, strict=True)]
    bond_rhs = [baumgarte(g, r, e, spec) for g, r, e in zip(quadratic, rate, residual, strict=True)]

    solved, bond_solved = thomas_solve(
        mass,
        [ca.horzcat(f, -b) for f, b in zip(forces, coupling, strict=True)],
        top_jacobians,
        [ca.horzcat(r, d) for r, d in zip(bond_rhs, strain_jacobians, strict=True)],
    )
    strain_response = sum(ca.dot(b, a[:, 1]) for b, a in zip(coupling, solved, strict=True)) + sum(
        ca.dot(d, f[:, 1]) for d, f in zip(strain_jacobians, bond_solved, strict=True)
    )
    modal_mass = strain_mass + strain_response
    damping = 2 * spec.axial_damping * ca.sqrt(stiffness * modal_mass)
    strain_force = sum(t[1][dofs] for t in terms) - stiffness * strain - damping * strain_rate
    strain_acceleration = (
        strain_force
        - sum(ca.dot(b, a[:, 0]) for b, a in zip(coupling, solved, strict=True))
        - sum(ca.dot(d, f[:, 0]) for d, f in zip(strain_jacobians, bond_solved, strict=True))
    ) / modal_mass
    accelerations = [a[:, 0] + strain_acceleration * a[:, 1] for a in solved]
    bond_forces = [f[:, 0] + strain_acceleration * f[:, 1] for f in bond_solved]

    qdd = ca.vertcat(*accelerations, strain_acceleration)
    coordinates = ca.vertcat(q_all, strain)
    full_mass = ca.vertcat(
        ca.horzcat(ca.diagcat(*mass), ca.vertcat(*coupling)),
        ca.horzcat(ca.vertcat(*coupling).T, strain_mass),
    )
    kkt_parts = [
        full_mass,
        ca.vertcat(*forces, strain_force),
        ca.jacobian(ca.vertcat(*residual), coordinates),
        ca.vertcat(*bond_rhs),
    ]
    outputs = chain_outputs(q, qd, upper_points, upper_rates, residual, rate, bond_forces, qdd)
    energy = potential + 0.5 * stiffness * strain**2
    energy += sum(element_energy(*args, p) for args in zip(local, local_rates, rest, strict=True))
    return SimpleNamespace(
        xdot=ca.vertcat(qd_all, strain_rate, qdd),
        kkt_parts=kkt_parts,
        outputs=outputs,
        energy=energy,
        q=q,
        qd=qd,
    )
