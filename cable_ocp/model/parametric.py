"""The symbolic rfe equations of one model structure, with the numbers as an input ``p``.

A :class:`ParametricModel` is built from a structure
(:func:`cable_ocp.model.parameters.structure_of`): its Functions take ``(x, u, p)``, where ``p``
holds the scene's numbers (length, densities,
coefficients, current, stiffnesses, Baumgarte gains;
:func:`cable_ocp.model.parameters.parameter_names`). It is built once per structure and process
(:func:`parametric_model`), and what is compiled from
it serves every scene of that structure. :class:`cable_ocp.model.cable.CableModel` binds ``p`` to
one scene's values. The equations are those of CONVENTIONS.md §3-4.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import cached_property, lru_cache
from types import SimpleNamespace

import casadi as ca

from cable_ocp.model.axial import elastic_graph
from cable_ocp.model.current import current_at
from cable_ocp.model.hydro import smooth_norm
from cable_ocp.model.joints import baumgarte, bending_energies, chain_outputs
from cable_ocp.model.kinematics import POSITION, relative_twist
from cable_ocp.model.kkt import thomas_solve
from cable_ocp.model.layout import INPUT_SIZE, INPUTS, OUTPUT_NAMES, top_inputs
from cable_ocp.model.parameters import is_on, symbolic_spec
from cable_ocp.model.rfe import element_functions, element_rotation

KKT_PART_NAMES = ("mass_matrix", "forces", "bond_jacobian", "bond_rhs")
# Structures kept per process (each holds its symbolic graph and compiled Functions).
STRUCTURE_CACHE_SIZE = 16


class ModelLayout:
    """Sizes and the state layout shared by the parametric and the bound model.

    Attributes
    ----------
    spec : ModelSpec
        Numbers (a bound model) or SX symbols (a parametric one) in its fields.
    dofs : int
        5, or 6 with torsion.
    element_count : int
        ``n + 1``.
    axial : int
        1 when the rope stretches (the line's strain ``s`` follows the elements' coordinates,
        :mod:`cable_ocp.model.axial`), else 0.
    """

    def __init__(self, spec):
        self.spec = spec
        self.dofs = spec.element.dofs
        self.element_count = spec.elements + 1
        self.axial = 1 if is_on(spec.axial_stiffness) else 0

    @property
    def state_size(self) -> int:
        """Length of the state vector."""
        return 2 * (self.dofs * self.element_count + self.axial)

    def element_lengths(self, top_length: ca.SX | float) -> list:
        """Lengths ``l_0 .. l_n`` (m): Delta/2 at both ends, Delta between, l_n from the winch."""
        delta = self.spec.segment_length
        lengths = [delta / 2] + [delta] * (self.element_count - 2) + [top_length]
        return lengths if self.element_count > 1 else [top_length]

    def coordinates(self, x) -> tuple[list, list]:
        """Split a state (SX or array) into per-element ``q_i`` and ``q'_i``."""
        size = self.state_size // 2
        q = [x[i * self.dofs : (i + 1) * self.dofs] for i in range(self.element_count)]
        qd = [
            x[size + i * self.dofs : size + (i + 1) * self.dofs] for i in range(self.element_count)
        ]
        return q, qd

    def strain(self, x) -> tuple:
        """The line's axial strain ``s`` and its rate (1/s) in a state of an elastic model."""
        if not self.axial:
            raise ValueError("this model's rope is rigid: it has no axial strain")
        half = self.state_size // 2
        return x[half - 1], x[2 * half - 1]


@lru_cache(maxsize=STRUCTURE_CACHE_SIZE)
def parametric_model(structure) -> ParametricModel:
    """The parametric model of a structure, built on the first call and shared afterwards."""
    return ParametricModel(structure)


class ParametricModel(ModelLayout):
    """Symbolic rfe model (CasADi SX) of one structure, its numbers an input ``p``.

    Attributes
    ----------
    structure : ModelSpec
        The structure it was built from (:func:`cable_ocp.model.parameters.structure_of`).
    x, u, p : SX
        State ``[q; q']``, inputs (:mod:`cable_ocp.model.layout`) and parameters.
    rhs : casadi.Function
        ``(x, u, p) -> x'`` with the bonds solved by the block Thomas elimination.
    kkt_parts : casadi.Function
        ``(x, u, p) ->`` block-diagonal mass matrix, forces, bond Jacobian and bond right-hand
        side, for the assembled sparse solve.
    outputs : casadi.Function
        ``(x, u, p) ->`` :data:`cable_ocp.model.layout.OUTPUT_NAMES`.
    energy : casadi.Function
        ``(x, u, p) ->`` kinetic plus potential energy (J), external force excluded.

    The four Functions are built when first used (the compiled structured path needs few of them).
    """

    def __init__(self, structure):
        spec, p = symbolic_spec(structure)
        super().__init__(spec)
        self.structure, self.p = structure, p
        self.x = ca.SX.sym("x", self.state_size)
        self.u = ca.SX.sym("u", INPUT_SIZE)
        self._memo: dict = {}

    def memo(self, key: tuple, build: Callable[[], object]):
        """A Function derived from this model (a compiled step), built once per ``key``."""
        if key not in self._memo:
            self._memo[key] = build()
        return self._memo[key]

    def function(
        self, name: str, outputs: list, output_names: list[str], cse: bool = True
    ) -> ca.Function:
        """An SX Function of ``(x, u, p)``, with common subexpressions eliminated by default."""
        return ca.Function(
            name, [self.x, self.u, self.p], outputs, ["x", "u", "p"], output_names, {"cse": cse}
        )

    # The flat Functions are built when first used: at n = 100 the expressions take 0.8 s and
    # eliminating their common subexpressions 4.8 s (rhs 1.6, kkt_parts 1.0, outputs 2.0), which
    # the compiled structured path (cable_ocp.model.structured) mostly does without. Common
    # subexpression elimination leaves 17 % fewer instructions (n = 15 and 100) and the same
    # numbers: it merges nodes that compute the same operation on the same operands.
    @cached_property
    def rhs(self) -> ca.Function:
        """``(x, u, p) -> x'`` (see the class attributes)."""
        return self.function("rhs", [self._graph.xdot], ["xdot"])

    @cached_property
    def kkt_parts(self) -> ca.Function:
        """``(x, u, p) ->`` mass matrix, forces, bond Jacobian and right-hand side."""
        return self.function("kkt_parts", self._graph.kkt_parts, list(KKT_PART_NAMES))

    @cached_property
    def outputs(self) -> ca.Function:
        """``(x, u, p) ->`` :data:`cable_ocp.model.layout.OUTPUT_NAMES`."""
        return self.function("outputs", self._graph.outputs, list(OUTPUT_NAMES))

    @cached_property
    def energy(self) -> ca.Function:
        """``(x, u, p) ->`` kinetic plus potential energy (J), external force excluded."""
        graph = self._graph
        if self.axial:
            energy = graph.energy
        else:
            energy = graph.potential + sum(
                graph.element_energy(qi, qdi, li, self.p)
                for qi, qdi, li in zip(graph.q, graph.qd, graph.lengths, strict=True)
            )
        energy += self._payload_energy(graph.q[0], graph.qd[0])
        return self.function("energy", [energy], ["energy"])

    def rhs_size(self) -> int:
        """Instructions of :attr:`rhs` before common-subexpression elimination (an upper bound)."""
        return self.memo(
            ("rhs", "uneliminated"),
            lambda: self.function("rhs", [self._graph.xdot], ["xdot"], cse=False).n_instructions(),
        )

    def output_values(self, x, u, p) -> dict[str, ca.DM]:
        """The outputs at one point, by name: :attr:`outputs` evaluated numerically.

        Until :attr:`outputs` is built, an un-eliminated twin is evaluated instead: the same
        operations, so the same numbers, built in 0.06 s against 2 s at n = 100.
        """
        if "outputs" in self.__dict__:
            return self.outputs(x=x, u=u, p=p)
        plain = self.memo(
            ("outputs", "uneliminated"),
            lambda: self.function("outputs", self._graph.outputs, list(OUTPUT_NAMES), cse=False),
        )
        return plain(x=x, u=u, p=p)

    @cached_property
    def bonds(self) -> ca.Function:
        """``(x, u, p) ->`` bond residual (m) and its rate (m/s): the outputs' two bond rows.

        The plant checks them at every sample; at n = 17 they cost a fraction of the outputs'
        3 ms, which solve for the accelerations too.
        """
        graph = self._graph.outputs
        rows = [graph[OUTPUT_NAMES.index(name)] for name in ("bond_residual", "bond_rate")]
        return self.function("bonds", rows, ["bond_residual", "bond_rate"])

    def bond_residual(self) -> ca.SX:
        """The bond residuals ``Phi`` (3 (n+1), m) as an SX expression of ``x, u, p``."""
        return self._graph.outputs[OUTPUT_NAMES.index("bond_residual")]

    @cached_property
    def _graph(self) -> SimpleNamespace:
        """The SX expressions of every flat Function, built on first use."""
        if self.axial:
            return elastic_graph(self)
        spec, p = self.spec, self.p
        element, element_energy = element_functions(spec.element, p)
        q, qd = self.coordinates(self.x)
        u = self.u
        top, top_velocity, top_acceleration, top_length, top_length_rate, top_length_acc = (
            top_inputs(u)
        )
        end_force = u[INPUTS.end_force]
        lengths = self.element_lengths(top_length)

        terms = [element(qi, qdi, li, p) for qi, qdi, li in zip(q, qd, lengths, strict=True)]
        mass = [t[0] for t in terms]
        axes = [t[2] for t in terms]
        axis_rates = [t[3] for t in terms]
        axis_quadratic = [t[4] for t in terms]
        top_jacobians = [t[5] for t in terms]

        q_all, qd_all = ca.vertcat(*q), ca.vertcat(*qd)
        potential, dissipation = self.spring_energies(q, qd, axes, axis_rates)
        chain_force = -ca.gradient(potential, q_all) - ca.gradient(dissipation, qd_all)
        forces = [
            t[1] + chain_force[i * self.dofs : (i + 1) * self.dofs] for i, t in enumerate(terms)
        ]
        mass[0], forces[0] = self.end_loads(mass[0], forces[0], q[0], qd[0], end_force)

        # Bond positions, rates and the quadratic part of their second derivative.
        upper_points = [qi[POSITION] + li * ei for qi, li, ei in zip(q, lengths, axes, strict=True)]
        lower_points = [qi[POSITION] for qi in q[1:]] + [top]
        upper_rates = [
            qdi[POSITION] + li * edi for qdi, li, edi in zip(qd, lengths, axis_rates, strict=True)
        ]
        upper_rates[-1] = upper_rates[-1] + top_length_rate * axes[-1]
        lower_rates = [qdi[POSITION] for qdi in qd[1:]] + [top_velocity]
        quadratic = [li * eq for li, eq in zip(lengths, axis_quadratic, strict=True)]
        quadratic[-1] = (
            quadratic[-1]
            + top_length_acc * axes[-1]
            + 2 * top_length_rate * axis_rates[-1]
            - top_acceleration
        )
        residual = [lo - up for lo, up in zip(lower_points, upper_points, strict=True)]
        rate = [lo - up for lo, up in zip(lower_rates, upper_rates, strict=True)]
        bond_rhs = [
            baumgarte(g, r, e, spec) for g, r, e in zip(quadratic, rate, residual, strict=True)
        ]

        accelerations, bond_forces = thomas_solve(mass, forces, top_jacobians, bond_rhs)
        qdd = ca.vertcat(*accelerations)
        kkt_parts = [
            ca.diagcat(*mass),
            ca.vertcat(*forces),
            ca.jacobian(ca.vertcat(*residual), q_all),
            ca.vertcat(*bond_rhs),
        ]
        outputs = chain_outputs(q, qd, upper_points, upper_rates, residual, rate, bond_forces, qdd)
        return SimpleNamespace(
            xdot=ca.vertcat(qd_all, qdd),
            kkt_parts=kkt_parts,
            outputs=outputs,
            potential=potential,
            element_energy=element_energy,
            q=q,
            qd=qd,
            lengths=lengths,
        )

    def spring_energies(self, q, qd, axes, axis_rates) -> tuple[ca.SX, ca.SX]:
        """Bending (and torsion) potential and Rayleigh dissipation of the joints."""
        spec = self.spec
        potential = ca.SX(0)
        dissipation = ca.SX(0)
        for i in range(1, self.element_count):
            joint_potential, joint_dissipation = bending_energies(
                axes[i - 1], axes[i], axis_rates[i - 1], axis_rates[i], spec
            )
            potential += joint_potential
            dissipation += joint_dissipation
        if spec.element.torsion:
            torsion = spec.torsional_stiffness / spec.segment_length
            rotations = [element_rotation(qi, True) for qi in q]
            q_all, qd_all = ca.vertcat(*q), ca.vertcat(*qd)
            for i in range(1, self.element_count):
                twist = relative_twist(rotations[i - 1], rotations[i])
                twist_rate = ca.jtimes(twist, q_all, qd_all)
                potential += 0.5 * torsion * twist**2
                dissipation += 0.5 * spec.torsion_damping * torsion * twist_rate**2
        return potential, dissipation

    def end_loads(self, mass, force, q_end, qd_end, end_force) -> tuple[ca.SX, ca.SX]:
        """Add the external end force and the payload (drag in the current at E) to element 0."""
        spec, payload = self.spec, self.spec.payload
        translational = ca.vertcat(end_force, ca.SX.zeros(self.dofs - 3))
        force = force + translational
        if is_on(payload.mass) or is_on(payload.volume):
            water = spec.water_density
            mass = mass + ca.diagcat(
                ca.SX.eye(3) * spec.payload_inertia, ca.SX(self.dofs - 3, self.dofs - 3)
            )
            payload_force = ca.vertcat(0, 0, -spec.payload_weight)
            if is_on(water) and is_on(payload.drag_area):
                current = current_at(spec.element.hydro, q_end[2])
                relative = qd_end[POSITION] - current
                coeff = 0.5 * water * payload.drag_coefficient * payload.drag_area
                payload_force = payload_force - coeff * smooth_norm(relative) * relative
            force = force + ca.vertcat(payload_force, ca.SX.zeros(self.dofs - 3))
        return mass, force

    def _payload_energy(self, q_end, qd_end) -> ca.SX:
        velocity = qd_end[POSITION]
        inertia, weight = self.spec.payload_inertia, self.spec.payload_weight
        return 0.5 * inertia * ca.dot(velocity, velocity) + weight * q_end[2]
