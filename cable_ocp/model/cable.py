"""The rfe cable model of a scene: state, inputs, right-hand side and outputs (CONVENTIONS.md §3-4).

Elements ``i = 0..n``: element 0 carries the free end ``E = A_0``, element ``n`` hangs from the top
point ``A_{n+1}`` carried by the vessel. The state is ``x = [q; q']`` with ``q`` stacked element by
element; the inputs ``u`` are the prescribed top motion, the top-element length set by the winch
(with its rates) and the external force at the end, so that one model serves every scene and every
way of driving it.

A :class:`CableModel` is the parametric model of its structure
(:class:`cable_ocp.model.parametric.ParametricModel`) with the scene's numbers bound: its symbolic
Functions ``(x, u)`` have them folded in as constants, its compiled ones call the structure's
library with them as the input ``p``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cached_property, lru_cache
from typing import Any

import casadi as ca
import numpy as np

from cable_ocp.model.hydro import HydroCoefficients
from cable_ocp.model.kinematics import TWIST_ANGLE
from cable_ocp.model.kkt import sparse_kkt_solve
from cable_ocp.model.layout import INPUT_NAMES, INPUT_SIZE
from cable_ocp.model.parameters import parameter_names, parameter_values, structure_of
from cable_ocp.model.parametric import ModelLayout, ParametricModel, parametric_model
from cable_ocp.model.rfe import ElementProperties
from cable_ocp.scene.axial_choice import axial_choice
from cable_ocp.scene.schema import Scene

__all__ = ["INPUT_NAMES", "INPUT_SIZE", "CableModel", "ModelSpec", "Payload", "spec_from_scene"]
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
        Its mass in air.
    volume : float, m^3
        The water it displaces (its buoyancy).
    drag_area : float, m^2
        The area across the flow that its drag acts on.
    drag_coefficient : float
        ``C_D`` of that area (its drag in the current at the end).
    added_mass_coefficient : float
        ``C_a``: the displaced water's mass it drags along, as a share of ``water * volume``.
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
        ``L``, the line out at ``phi = 0``.
    top_length : float, m
        The top element at ``phi = 0`` (the scene's graded mesh, ``Scene.mesh``); the elements
        below share the rest of the line.
    element : ElementProperties
        The material data every element shares (:class:`~cable_ocp.model.rfe.ElementProperties`).
    bending_stiffness : float, N m^2
        ``EI``; the spring between two elements is ``k = EI / Delta``. 0 switches bending off.
    torsional_stiffness : float, N m^2
        ``G I_p`` (eq. 37); used only with torsion.
    bending_damping, torsion_damping : float, s
        Rayleigh time constants: damping = constant * spring stiffness.
    gravity : float, m/s^2
        ``g``.
    water_density : float, kg/m^3
        0 in air.
    baumgarte_alpha, baumgarte_beta : float, 1/s
        Gains of ``Phi'' + 2 alpha Phi' + beta^2 Phi = 0``.
    payload : Payload
        The point mass at the free end (none: all zero).
    axial_stiffness : float, N
        ``EA`` of an elastic rope (:mod:`cable_ocp.model.axial`); 0: rigid, the paper's rope.
    axial_damping : float
        Damping ratio of the elastic rope's axial mode.
    """

    elements: int
    cable_length: float
    top_length: float
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
    axial_stiffness: float = 0.0
    axial_damping: float = 0.0

    @property
    def segment_length(self) -> float:
        """``Delta = (L - l_top) / (n - 1/2)`` (m): L / n on a uniform mesh."""
        return (self.cable_length - self.top_length) / (self.elements - 0.5)

    @property
    def payload_weight(self) -> float:
        """The payload's weight less its buoyancy, ``(M - rho_w V) g`` (N; negative: it floats)."""
        return (self.payload.mass - self.water_density * self.payload.volume) * self.gravity

    @property
    def payload_inertia(self) -> float:
        """The payload's mass with the water it drags along, ``M + C_a rho_w V`` (kg)."""
        payload = self.payload
        return payload.mass + payload.added_mass_coefficient * self.water_density * payload.volume


def spec_from_scene(scene, elements: int | None = None) -> ModelSpec:
    """Model data for a scene, optionally with another number of elements (a reduced model).

    Parameters
    ----------
    scene : Scene
    elements : int, optional
        Overrides ``scene.model.elements``.
    """
    cable, env, hyd = scene.cable, scene.environment, scene.hydrodynamics
    water = env.fluid_density
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
            quadrature_points=hyd.quadrature_points,
            **_current(env),
        )
    props = ElementProperties(
        mass_per_length=cable.density * area,
        diameter=cable.diameter,
        submerged_weight_per_length=(cable.density - water) * area * env.gravity,
        torsion=scene.model.torsion,
        hydro=hydro,
    )
    elements = elements or scene.model.elements
    elastic = axial_choice(scene).elastic
    return ModelSpec(
        elements=elements,
        cable_length=cable.length,
        top_length=scene.mesh(elements)[1],
        element=props,
        bending_stiffness=cable.bending_stiffness if scene.model.bending else 0.0,
        torsional_stiffness=cable.torsional_stiffness,
        bending_damping=cable.bending_damping,
        torsion_damping=cable.torsion_damping,
        gravity=env.gravity,
        water_density=water,
        baumgarte_alpha=scene.numerics.baumgarte_alpha,
        baumgarte_beta=scene.numerics.baumgarte_beta,
        payload=_payload(scene.end.payload),
        axial_stiffness=cable.axial_stiffness_value if elastic else 0.0,
        axial_damping=cable.axial_damping if elastic else 0.0,
    )


def _current(env) -> dict:
    """The current fields of :class:`HydroCoefficients` for a scene's ``[environment]``.

    A profile whose rows all carry one current is that uniform current: the same model, so the
    same numbers on every path (modelled as a table, the compiled n = 100 step at -O3 differed
    from the uniform current's in the last bits, 1e-13 m).
    """
    rows = env.current_profile
    if len({(row.u, row.v) for row in rows}) == 1:
        return {"current": (rows[0].u, rows[0].v, 0.0)}
    return {
        "current": tuple(env.current),
        "current_z": tuple(row.z for row in rows),
        "current_u": tuple(row.u for row in rows),
        "current_v": tuple(row.v for row in rows),
    }


def _payload(payload) -> Payload:
    """The model's payload from a scene's ``[end.payload]`` (none: a payload of zero mass)."""
    if payload is None:
        return Payload()
    return Payload(
        mass=payload.mass,
        volume=payload.volume,
        drag_area=payload.drag_area,
        drag_coefficient=payload.drag,
        added_mass_coefficient=payload.added_mass,
    )


@lru_cache(maxsize=MODEL_CACHE_SIZE)
def cached_model(spec: ModelSpec) -> CableModel:
    """The model of ``spec``, built on the first call and shared by later ones in this process.

    A model is immutable once built (its memo only adds derived Functions), so sharing is safe;
    models of one structure share one :class:`~cable_ocp.model.parametric.ParametricModel`.
    """
    return CableModel(spec)


class CableModel(ModelLayout):
    """The rfe model of one scene (CasADi SX): a parametric model with the scene's numbers bound.

    Attributes
    ----------
    spec : ModelSpec
    parametric : ParametricModel
        The model of this structure, shared by every spec that differs only in its numbers
        (or the one given: a model of a paid-out line, :mod:`cable_ocp.model.line_models`).
    parameters : array
        The numbers bound to its input ``p`` (names: :attr:`parameter_names`).
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

    def __init__(self, spec: ModelSpec, parametric: ParametricModel | None = None):
        if spec.elements < 1:
            raise ValueError(f"elements = {spec.elements} is out of range: must be >= 1")
        super().__init__(spec)
        self.parametric = parametric or parametric_model(structure_of(spec))
        self.parameters = parameter_values(spec)
        self.x, self.u = self.parametric.x, self.parametric.u
        self._memo: dict = {}

    def memo(self, key: tuple, build: Callable[[], Any]) -> Any:
        """A Function derived from this model (a step, a map) or a cache, built once per key."""
        if key not in self._memo:
            self._memo[key] = build()
        return self._memo[key]

    @classmethod
    def from_scene(cls, scene, elements: int | None = None) -> CableModel:
        """The model a scene asks for (``elements`` overrides its ``n``), built once per process.

        Models are kept per :class:`ModelSpec` (:func:`cached_model`), so repeated simulations
        and optimisations of one scene reuse the symbolic model and its compiled Functions.
        Raises TypeError when ``scene`` is not a :class:`~cable_ocp.scene.schema.Scene`.
        """
        if not isinstance(scene, Scene):
            raise TypeError(
                f"CableModel.from_scene: scene must be a Scene (co.load_scene(...)); got "
                f"{type(scene).__name__}"
            )
        return cached_model(spec_from_scene(scene, elements))

    # ----------------------------------------------------------------------------------------
    @cached_property
    def parameter_names(self) -> list[str]:
        """Names of the entries of :attr:`parameters` (dotted paths into the spec)."""
        return parameter_names(self.spec)

    @cached_property
    def state_names(self) -> list[str]:
        """Names of the state entries, e.g. ``psi_3`` and ``d_psi_3`` (its rate)."""
        coords = ["x", "y", "z", "psi", "theta", "phi"][: self.dofs]
        names = [f"{c}_{i}" for i in range(self.element_count) for c in coords]
        names += ["strain"] * self.axial
        return names + [f"d_{name}" for name in names]

    def bind(self, function: ca.Function, **values: float) -> ca.Function:
        """A Function with its input ``p`` set to :attr:`parameters` (and others to ``values``).

        An SX Function stays SX, with the numbers folded in as constants (the same expression as
        a model built with them); any other (a compiled library) is wrapped in an MX call. A
        mapped input (``p`` of a map over k calls) takes the one value for every call.
        """
        kind = ca.SX if function.is_a("SXFunction") else ca.MX
        fixed = {"p": self.parameters, **values}
        names = [name for name in function.name_in() if name not in fixed]
        arguments = {name: kind.sym(name, function.sparsity_in(name)) for name in names}
        constants = {name: ca.DM(value) for name, value in fixed.items()}
        results = function.call({**arguments, **constants})
        return ca.Function(
            function.name(),
            list(arguments.values()),
            [results[name] for name in function.name_out()],
            names,
            function.name_out(),
            {"cse": True} if kind is ca.SX else {},
        )

    def output_values(self, x: np.ndarray, u: np.ndarray) -> dict[str, np.ndarray]:
        """The outputs at one state and input, by name (see :attr:`outputs`), as arrays.

        Evaluated on the parametric model with :attr:`parameters`: no bound Function is built
        (binding the outputs of a model of n = 100 costs 0.7 s, evaluating them a millisecond),
        nor an eliminated one if none is built yet (:meth:`ParametricModel.output_values`).
        """
        results = self.parametric.output_values(x, u, self.parameters)
        return {name: np.array(value) for name, value in results.items()}

    def bond_values(self, x: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The bond residual (m) and its rate (m/s) at one state and input, as arrays."""
        residual, rate = self.parametric.bonds(x, u, self.parameters)
        return np.array(residual), np.array(rate)

    @cached_property
    def rhs(self) -> ca.Function:
        """``(x, u) -> x'`` (see the class attributes)."""
        return self.bind(self.parametric.rhs)

    @cached_property
    def outputs(self) -> ca.Function:
        """``(x, u) ->`` joints, velocities, bond residuals and forces, tensions, accelerations."""
        return self.bind(self.parametric.outputs)

    @cached_property
    def energy(self) -> ca.Function:
        """``(x, u) ->`` kinetic plus potential energy (J), external force excluded."""
        return self.bind(self.parametric.energy)

    # ----------------------------------------------------------------------------------------
    @cached_property
    def rhs_sparse(self) -> ca.Function:
        """Right-hand side by the assembled sparse KKT solve (independent of the Thomas path)."""
        x, u = ca.MX.sym("x", self.state_size), ca.MX.sym("u", INPUT_SIZE)
        mass, force, jac, rhs = self.bind(self.parametric.kkt_parts)(x, u)
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
