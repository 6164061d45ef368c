"""The symbolic rfe cable model: state, inputs, right-hand side and outputs (CONVENTIONS.md §3-4).

Elements ``i = 0..n``: element 0 carries the free end ``E = A_0``, element ``n`` hangs from the top
point ``A_{n+1}`` carried by the vessel. The state is ``x = [q; q']`` with ``q`` stacked element by
element; the inputs ``u`` are the prescribed top motion, the top-element length set by the winch
(with its rates) and the external force at the end, so that one model serves every scene and every
way of driving it.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cached_property, lru_cache

import casadi as ca
import numpy as np

from cable_ocp.hydro import HydroCoefficients, smooth_norm
from cable_ocp.kinematics import POSITION, TWIST_ANGLE, relative_twist
from cable_ocp.kkt import sparse_kkt_solve, thomas_solve
from cable_ocp.rfe import ElementProperties, element_functions, element_rotation

INPUT_NAMES = (
    "top_x", "top_y", "top_z",
    "top_vx", "top_vy", "top_vz",
    "top_ax", "top_ay", "top_az",
    "top_length", "top_length_rate", "top_length_acceleration",
    "end_force_x", "end_force_y", "end_force_z",
)  # fmt: skip
INPUT_SIZE = len(INPUT_NAMES)
# Models kept per process by CableModel.from_scene (each holds its symbolic graph and compiled
# Functions; a sweep of many fidelities evicts the least recently used).
MODEL_CACHE_SIZE = 32
# Below this |cos(theta)| an element is taken to lie along +-y, where the Euler chart is singular.
SINGULAR_COS_THETA = 1e-3


@dataclass(frozen=True)
class Payload:
    """A point mass at the free end ``A_0``.

    Attributes
    ----------
    mass : float, kg
    volume : float, m^3
    drag_area : float, m^2
    drag_coefficient : float
    added_mass_coefficient : float
    """

    mass: float = 0.0
    volume: float = 0.0
    drag_area: float = 0.0
    drag_coefficient: float = 1.0
    added_mass_coefficient: float = 1.0


@dataclass(frozen=True)
class ModelSpec:
    """Everything that fixes the symbolic model (and nothing that only drives it).

    Attributes
    ----------
    elements : int
        ``n``; the model has ``n + 1`` rigid elements.
    cable_length : float, m
    element : ElementProperties
    bending_stiffness : float, N m^2
        ``EI``; the spring between two elements is ``k = EI / Delta``. 0 switches bending off.
    torsional_stiffness : float, N m^2
        ``G I_p`` (eq. 37); used only with torsion.
    bending_damping, torsion_damping : float, s
        Rayleigh time constants: damping = constant * spring stiffness.
    gravity : float, m/s^2
    water_density : float, kg/m^3
        0 in air.
    baumgarte_alpha, baumgarte_beta : float, 1/s
        Gains of ``Phi'' + 2 alpha Phi' + beta^2 Phi = 0``.
    payload : Payload
    """

    elements: int
    cable_length: float
    element: ElementProperties
    bending_stiffness: float
    torsional_stiffness: float
    bending_damping: float
    torsion_damping: float
    gravity: float
    water_density: float
    baumgarte_alpha: float
    baumgarte_beta: float
    payload: Payload = field(default_factory=Payload)

    @property
    def segment_length(self) -> float:
        """Delta = L / n (m)."""
        return self.cable_length / self.elements


def spec_from_scene(scene, elements: int | None = None) -> ModelSpec:
    """Model data for a scene, optionally with another number of elements (a reduced model).

    Parameters
    ----------
    scene : Scene
    elements : int, optional
        Overrides ``scene.model.elements``.
    """
    cable, env, hyd, end = scene.cable, scene.environment, scene.hydrodynamics, scene.end
    water = env.water_density if env.submerged else 0.0
    area = cable.cross_section_area
    hydro = None
    if water > 0:
        hydro = HydroCoefficients(
            water_density=water,
            diameter=cable.diameter,
            area=area,
            drag_normal=hyd.drag_normal if hyd.drag else 0.0,
            drag_axial=hyd.drag_axial if hyd.drag else 0.0,
            added_mass_normal=hyd.added_mass_normal if hyd.added_mass else 0.0,
            added_mass_axial=hyd.added_mass_axial if hyd.added_mass else 0.0,
            current=tuple(env.current),
            quadrature_points=hyd.quadrature_points,
        )
    props = ElementProperties(
        mass_per_length=cable.density * area,
        diameter=cable.diameter,
        submerged_weight_per_length=(cable.density - water) * area * env.gravity,
        torsion=scene.model.torsion,
        hydro=hydro,
    )
    return ModelSpec(
        elements=elements or scene.model.elements,
        cable_length=cable.length,
        element=props,
        bending_stiffness=cable.bending_stiffness if scene.model.bending else 0.0,
        torsional_stiffness=cable.torsional_stiffness,
        bending_damping=cable.bending_damping,
        torsion_damping=cable.torsion_damping,
        gravity=env.gravity,
        water_density=water,
        baumgarte_alpha=scene.numerics.baumgarte_alpha,
        baumgarte_beta=scene.numerics.baumgarte_beta,
        payload=Payload(
            mass=end.payload_mass,
            volume=end.payload_volume,
            drag_area=end.payload_drag_area,
            drag_coefficient=end.payload_drag,
            added_mass_coefficient=end.payload_added_mass,
        ),
    )


@lru_cache(maxsize=MODEL_CACHE_SIZE)
def cached_model(spec: ModelSpec) -> CableModel:
    """The model of ``spec``, built on the first call and shared by later ones in this process.

    A model is immutable once built (its memo only adds derived Functions), so sharing is safe.
    """
    return CableModel(spec)


class CableModel:
    """Symbolic rfe model of the cable (CasADi SX), built once per fidelity.

    Attributes
    ----------
    spec : ModelSpec
    x : SX
        State ``[q; q']``, size ``2 * dofs * (n + 1)``.
    u : SX
        Inputs, see :data:`INPUT_NAMES`.
    rhs : casadi.Function
        ``(x, u) -> x'`` with the bonds solved by the block Thomas elimination.
    rhs_sparse : casadi.Function
        The same right-hand side from the assembled KKT matrix and a sparse solver (cross-check).
    outputs : casadi.Function
        ``(x, u) ->`` joints (3 x n+2, m), joint_velocities (m/s), bond_residual (m),
        bond_rate (m/s), bond_forces (3 x n+1, N), tensions (n+1, N), accelerations.
    energy : casadi.Function
        ``(x, u) ->`` kinetic plus potential energy (J), external force excluded.
    """

    def __init__(self, spec: ModelSpec):
        if spec.elements < 1:
            raise ValueError(f"elements = {spec.elements} is out of range: must be >= 1")
        self.spec = spec
        self.dofs = spec.element.dofs
        self.element_count = spec.elements + 1
        size = self.dofs * self.element_count
        self.x = ca.SX.sym("x", 2 * size)
        self.u = ca.SX.sym("u", INPUT_SIZE)
        self._build()
        self._memo: dict = {}

    def memo(self, key: tuple, build: Callable[[], ca.Function]) -> ca.Function:
        """A Function derived from this model (a step, a map), built once per ``key``."""
        if key not in self._memo:
            self._memo[key] = build()
        return self._memo[key]

    @classmethod
    def from_scene(cls, scene, elements: int | None = None) -> CableModel:
        """The model a scene asks for (``elements`` overrides its ``n``), built once per process.

        Models are kept per :class:`ModelSpec` (:func:`cached_model`), so repeated simulations
        and optimisations of one scene reuse the symbolic model and its compiled Functions.
        """
        return cached_model(spec_from_scene(scene, elements))

    # ----------------------------------------------------------------------------------------
    @property
    def state_size(self) -> int:
        """Length of the state vector."""
        return self.x.numel()

    @cached_property
    def state_names(self) -> list[str]:
        """Names of the state entries, e.g. ``psi_3`` and ``d_psi_3`` (its rate)."""
        coords = ["x", "y", "z", "psi", "theta", "phi"][: self.dofs]
        names = [f"{c}_{i}" for i in range(self.element_count) for c in coords]
        return names + [f"d_{name}" for name in names]

    def element_lengths(self, top_length: ca.SX | float) -> list:
        """Lengths ``l_0 .. l_n`` (m): Delta/2 at both ends, Delta between, l_n from the winch."""
        delta = self.spec.segment_length
        lengths = [delta / 2] + [delta] * (self.element_count - 2) + [top_length]
        return lengths if self.element_count > 1 else [top_length]

    def coordinates(self, x) -> tuple[list, list]:
        """Split a state (SX or array) into per-element ``q_i`` and ``q'_i``."""
        size = self.dofs * self.element_count
        q = [x[i * self.dofs : (i + 1) * self.dofs] for i in range(self.element_count)]
        qd = [
            x[size + i * self.dofs : size + (i + 1) * self.dofs] for i in range(self.element_count)
        ]
        return q, qd

    # ----------------------------------------------------------------------------------------
    def _build(self) -> None:
        spec = self.spec
        element, element_energy = element_functions(spec.element)
        q, qd = self.coordinates(self.x)
        u = self.u
        top, top_velocity, top_acceleration = u[0:3], u[3:6], u[6:9]
        top_length, top_length_rate, top_length_acc = u[9], u[10], u[11]
        end_force = u[12:15]
        lengths = self.element_lengths(top_length)

        terms = [element(qi, qdi, li) for qi, qdi, li in zip(q, qd, lengths, strict=True)]
        mass = [t[0] for t in terms]
        axes = [t[2] for t in terms]
        axis_rates = [t[3] for t in terms]
        axis_quadratic = [t[4] for t in terms]
        top_jacobians = [t[5] for t in terms]

        q_all, qd_all = ca.vertcat(*q), ca.vertcat(*qd)
        potential, dissipation = self._spring_energies(q, qd, axes, axis_rates)
        chain_force = -ca.gradient(potential, q_all) - ca.gradient(dissipation, qd_all)
        forces = [
            t[1] + chain_force[i * self.dofs : (i + 1) * self.dofs] for i, t in enumerate(terms)
        ]
        mass[0], forces[0] = self.end_loads(mass[0], forces[0], qd[0], end_force)

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
        alpha, beta = spec.baumgarte_alpha, spec.baumgarte_beta
        bond_rhs = [
            g - 2 * alpha * r - beta**2 * p
            for g, r, p in zip(quadratic, rate, residual, strict=True)
        ]

        accelerations, bond_forces = thomas_solve(mass, forces, top_jacobians, bond_rhs)
        qdd = ca.vertcat(*accelerations)
        # Common subexpression elimination: 17 % fewer instructions at n = 15 and 100.
        self.rhs = ca.Function(
            "rhs", [self.x, u], [ca.vertcat(qd_all, qdd)], ["x", "u"], ["xdot"], {"cse": True}
        )

        self._sparse_parts = ca.Function(
            "kkt_parts",
            [self.x, u],
            [
                ca.diagcat(*mass),
                ca.vertcat(*forces),
                ca.jacobian(ca.vertcat(*residual), q_all),
                ca.vertcat(*bond_rhs),
            ],
        )
        joints = ca.horzcat(*[qi[POSITION] for qi in q], upper_points[-1])
        joint_velocities = ca.horzcat(*[qdi[POSITION] for qdi in qd], upper_rates[-1])
        forces_matrix = ca.horzcat(*bond_forces)
        tensions = ca.vertcat(*[ca.norm_2(f) for f in bond_forces])
        self.outputs = ca.Function(
            "outputs",
            [self.x, u],
            [
                joints,
                joint_velocities,
                ca.vertcat(*residual),
                ca.vertcat(*rate),
                forces_matrix,
                tensions,
                qdd,
            ],
            ["x", "u"],
            [
                "joints",
                "joint_velocities",
                "bond_residual",
                "bond_rate",
                "bond_forces",
                "tensions",
                "accelerations",
            ],
        )
        energy = potential + sum(
            element_energy(qi, qdi, li) for qi, qdi, li in zip(q, qd, lengths, strict=True)
        )
        energy += self._payload_energy(q[0], qd[0])
        self.energy = ca.Function("energy", [self.x, u], [energy], ["x", "u"], ["energy"])

    def _spring_energies(self, q, qd, axes, axis_rates) -> tuple[ca.SX, ca.SX]:
        """Bending (and torsion) potential and Rayleigh dissipation of the joints."""
        spec = self.spec
        bending = spec.bending_stiffness / spec.segment_length
        potential = ca.SX(0)
        dissipation = ca.SX(0)
        for i in range(1, self.element_count):
            potential += bending * (1 - ca.dot(axes[i - 1], axes[i]))
            relative_rate = axis_rates[i] - axis_rates[i - 1]
            dissipation += (
                0.5 * spec.bending_damping * bending * ca.dot(relative_rate, relative_rate)
            )
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

    def end_loads(self, mass, force, qd_end, end_force) -> tuple[ca.SX, ca.SX]:
        """Add the external end force and the payload to element 0."""
        spec, payload = self.spec, self.spec.payload
        translational = ca.vertcat(end_force, ca.SX.zeros(self.dofs - 3))
        force = force + translational
        if payload.mass > 0 or payload.volume > 0:
            water = spec.water_density
            added = payload.added_mass_coefficient * water * payload.volume
            mass = mass + ca.diagcat(
                ca.SX.eye(3) * (payload.mass + added), ca.SX(self.dofs - 3, self.dofs - 3)
            )
            weight = (payload.mass - water * payload.volume) * spec.gravity
            payload_force = ca.vertcat(0, 0, -weight)
            if water > 0 and payload.drag_area > 0:
                relative = qd_end[POSITION] - ca.DM(spec.element.hydro.current)
                coeff = 0.5 * water * payload.drag_coefficient * payload.drag_area
                payload_force = payload_force - coeff * smooth_norm(relative) * relative
            force = force + ca.vertcat(payload_force, ca.SX.zeros(self.dofs - 3))
        return mass, force

    def _payload_energy(self, q_end, qd_end) -> ca.SX:
        payload, water = self.spec.payload, self.spec.water_density
        velocity = qd_end[POSITION]
        inertia = payload.mass + payload.added_mass_coefficient * water * payload.volume
        weight = (payload.mass - water * payload.volume) * self.spec.gravity
        return 0.5 * inertia * ca.dot(velocity, velocity) + weight * q_end[2]

    # ----------------------------------------------------------------------------------------
    @cached_property
    def rhs_sparse(self) -> ca.Function:
        """Right-hand side by the assembled sparse KKT solve (independent of the Thomas path)."""
        x, u = ca.MX.sym("x", self.state_size), ca.MX.sym("u", INPUT_SIZE)
        mass, force, jac, rhs = self._sparse_parts(x, u)
        qdd, bond_forces = sparse_kkt_solve(mass, force, jac, rhs)
        size = self.state_size // 2
        return ca.Function(
            "rhs_sparse",
            [x, u],
            [ca.vertcat(x[size:], qdd), ca.reshape(bond_forces, 3, self.element_count)],
            ["x", "u"],
            ["xdot", "bond_forces"],
        )

    def jacobian(self, wrt: str = "x") -> ca.Function:
        """Jacobian of the right-hand side w.r.t. the state (``"x"``) or the inputs (``"u"``).

        Returns
        -------
        casadi.Function
            ``(x, u) -> d xdot / d wrt``; its ``sparsity_out(0)`` shows the structure.
        """
        if wrt not in ("x", "u"):
            raise ValueError(f"wrt = {wrt!r}: must be 'x' (state) or 'u' (inputs)")
        variable = self.x if wrt == "x" else self.u
        xdot = self.rhs(self.x, self.u)
        return ca.Function(
            f"jac_xdot_{wrt}", [self.x, self.u], [ca.jacobian(xdot, variable)], ["x", "u"], ["jac"]
        )

    def check_regular(self, x: np.ndarray) -> None:
        """Raise if an element of the state lies on the singular set of the Euler chart.

        Parameters
        ----------
        x : array (state_size,) or (state_size, k)
        """
        states = np.asarray(x, dtype=float).reshape(self.state_size, -1)
        theta = states[4 : self.state_size // 2 : self.dofs]
        bad = np.argwhere(np.abs(np.cos(theta)) < SINGULAR_COS_THETA)
        if bad.size:
            element, column = bad[0]
            raise ValueError(
                f"element {element} lies along the y axis (theta = "
                f"{theta[element, column]:.6f} rad, |cos theta| < {SINGULAR_COS_THETA}): the "
                "Euler-angle chart psi/theta is singular there. Rotate the scene about z so that "
                "no element is horizontal along y."
            )

    def twist_angle_index(self) -> slice:
        """Indices of the twist angles in the state (torsion models only)."""
        if not self.spec.element.torsion:
            raise ValueError("this model has no torsion (5-DOF elements)")
        return slice(TWIST_ANGLE, self.state_size // 2, self.dofs)
