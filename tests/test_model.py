"""The model against independent references: sparse KKT, the paper's trace formula, FD."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from cable_ocp.drive.drive import Drive
from cable_ocp.model.cable import INPUT_SIZE, CableModel
from cable_ocp.model.kinematics import axis_direction, rotation_matrix
from cable_ocp.model.layout import INPUTS
from cable_ocp.model.rfe import (
    ElementProperties,
    added_mass_energy,
    closed_form_kinetic_energy,
    element_functions,
    kinetic_energy,
)
from cable_ocp.scene.schema import load_scene
from cable_ocp.simulation.statics import equilibrium, rest_inputs

TORSION = pytest.mark.parametrize("torsion", [False, True], ids=["5dof", "6dof"])
# Everything on: drag, anisotropic added mass (C_at != C_a, both non-zero) and a current.
FULL_PHYSICS = {
    "model.elements": 6,
    "environment.current": [0.4, -0.2, 0.05],
    "hydrodynamics.added_mass_axial": 0.3,
}


@pytest.fixture(scope="module")
def full_model(models_dir):
    """``torsion -> CableModel`` of hanging.toml at n = 6 with all forces on, cached."""
    cache = {}

    def get(torsion: bool) -> CableModel:
        if torsion not in cache:
            overrides = {**FULL_PHYSICS, "model.torsion": torsion}
            cache[torsion] = CableModel.from_scene(
                load_scene(models_dir / "hanging.toml", overrides)
            )
        return cache[torsion]

    return get


def random_state(model: CableModel, rng: np.random.Generator) -> np.ndarray:
    """A generic state: positions off the bonds, angles away from the singular set, random rates."""
    q = rng.normal(size=(model.element_count, model.dofs))
    q[:, :3] *= 50.0  # m
    q[:, 3] = rng.uniform(-np.pi, np.pi, model.element_count)
    q[:, 4] = rng.uniform(-1.2, 1.2, model.element_count)
    qd = rng.normal(size=(model.element_count, model.dofs))
    return np.concatenate([q.ravel(), qd.ravel()])


def random_inputs(rng: np.random.Generator) -> np.ndarray:
    """Top motion, a top-element length in the winch's range (2..30 m), rates and an end force."""
    u = rng.normal(size=INPUT_SIZE)
    u[INPUTS.top] *= 10.0  # m
    u[INPUTS.top_length] = rng.uniform(2.0, 30.0)  # m
    u[INPUTS.end_force] *= 1e4  # N
    return u


def max_relative(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.abs(np.asarray(a) - np.asarray(b)).max() / np.abs(np.asarray(b)).max())


# ----------------------------------------------------------------------------------------------
@TORSION
def test_thomas_agrees_with_sparse_kkt(full_model, torsion, validation):
    """Block Thomas (rhs, outputs) vs assembled sparse KKT (rhs_sparse): 1e-9 relative.

    xdot and the bond forces (3 x n+1), at random states and inputs.
    """
    model = full_model(torsion)
    rng = np.random.default_rng(20240611 + torsion)
    worst = 0.0
    for _ in range(4):
        x, u = random_state(model, rng), random_inputs(rng)
        xdot = np.array(model.rhs(x, u)).ravel()
        forces = model.output_values(x, u)["bond_forces"]
        xdot_sparse, forces_sparse = (np.array(v) for v in model.rhs_sparse(x, u))
        assert forces.shape == forces_sparse.shape == (3, model.element_count)
        assert np.all(np.isfinite(xdot))
        worst = max(
            worst, max_relative(xdot, xdot_sparse.ravel()), max_relative(forces, forces_sparse)
        )
    validation(f"block Thomas KKT solve, {model.dofs} DOF, all forces on", "second formulation",
               "assembled sparse KKT (csparse)", "max relative difference of x' and bond forces",
               f"{worst:.1e}", "< 1e-9")  # fmt: skip
    assert worst < 1e-9


# ----------------------------------------------------------------------------------------------
# The paper's kinetic energy (eq. 3-5), built in the paper's axes: paper (X, Y, Z) = (x, z, -y).
def _rz(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _ry(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def _rx(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _drz(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[-s, -c, 0.0], [c, -s, 0.0], [0.0, 0.0, 0.0]])


def _dry(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[-s, 0.0, c], [0.0, 0.0, 0.0], [-c, 0.0, -s]])


def _drx(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[0.0, 0.0, 0.0], [0.0, -s, -c], [0.0, c, -s]])


def _angles(q):
    return q[3], q[4], (q[5] if len(q) > 5 else 0.0)


def paper_b(q: np.ndarray) -> np.ndarray:
    """Homogeneous B = [[R, r], [0, 1]] (eq. 3), R = Rz(psi) Ry(theta) Rx(phi), in paper axes."""
    psi, theta, phi = _angles(q)
    b = np.eye(4)
    b[:3, :3] = _rz(psi) @ _ry(theta) @ _rx(phi)
    b[:3, 3] = [q[0], q[2], -q[1]]
    return b


def paper_b_rate(q: np.ndarray, qd: np.ndarray) -> np.ndarray:
    """dB/dt along q + t qd, analytically (chain rule over the three elementary rotations)."""
    psi, theta, phi = _angles(q)
    dpsi, dtheta, dphi = _angles(qd)
    rate = np.zeros((4, 4))
    rate[:3, :3] = (
        _drz(psi) @ _ry(theta) @ _rx(phi) * dpsi
        + _rz(psi) @ _dry(theta) @ _rx(phi) * dtheta
        + _rz(psi) @ _ry(theta) @ _drx(phi) * dphi
    )
    rate[:3, 3] = [qd[0], qd[2], -qd[1]]
    return rate


def paper_kinetic_energy(q, qd, length, mass_per_length, diameter) -> float:
    """E = 1/2 tr(B' H B'^T) (eq. 4) with H of eq. 5 for a uniform rod along x'."""
    m, a = mass_per_length * length, length / 2
    hx, hyz = m * length**2 / 3, m * diameter**2 / 16
    h = np.array(
        [[hx, 0.0, 0.0, m * a], [0.0, hyz, 0.0, 0.0], [0.0, 0.0, hyz, 0.0], [m * a, 0.0, 0.0, m]]
    )
    rate = paper_b_rate(q, qd)
    return 0.5 * np.trace(rate @ h @ rate.T)


def test_paper_b_rate_matches_finite_differences():
    """The reference's analytic B' against central differences of B(q + t qd): 1e-8 absolute."""
    rng = np.random.default_rng(5)
    for dofs in (5, 6):
        q, qd = rng.normal(size=dofs) * 2, rng.normal(size=dofs)
        eps = 1e-5
        fd = (paper_b(q + eps * qd) - paper_b(q - eps * qd)) / (2 * eps)
        np.testing.assert_allclose(paper_b_rate(q, qd), fd, rtol=0, atol=1e-8)


@TORSION
def test_kinetic_energy_matches_paper_trace_formula(torsion, validation):
    """rfe.kinetic_energy vs 1/2 tr(B' H B'^T) in the paper's axes (analytic B'): 1e-12 relative."""
    mu, diameter = 25.0, 0.07
    props = ElementProperties(
        mass_per_length=mu,
        diameter=diameter,
        submerged_weight_per_length=200.0,
        torsion=torsion,
        hydro=None,
    )
    dofs = props.dofs
    q, qd, length = ca.SX.sym("q", dofs), ca.SX.sym("qd", dofs), ca.SX.sym("length")
    energy = ca.Function("T", [q, qd, length], [kinetic_energy(q, qd, length, props)])
    rng = np.random.default_rng(11 + dofs)
    worst = 0.0
    for _ in range(6):
        qv, qdv, lv = rng.normal(size=dofs) * 2, rng.normal(size=dofs), rng.uniform(2.0, 30.0)
        qdv[3:] *= 0.3  # rad/s
        expected = paper_kinetic_energy(qv, qdv, lv, mu, diameter)
        worst = max(worst, abs(float(energy(qv, qdv, lv)) / expected - 1))
    validation(f"element kinetic energy, {dofs} DOF", "second formulation",
               "paper's trace formula eq. 3-5 (analytic B')", "max relative difference",
               f"{worst:.1e}", "<= 1e-12")  # fmt: skip
    assert worst <= 1e-12


def test_closed_form_energy_matches_trace_form_with_added_mass(full_model, validation):
    """The 5-DOF closed form vs trace form + Gauss-integrated added mass (C_at != C_a): 1e-12."""
    props = full_model(False).spec.element
    q, qd, length = ca.SX.sym("q", 5), ca.SX.sym("qd", 5), ca.SX.sym("length")
    axis = axis_direction(q[3], q[4])
    reference = kinetic_energy(q, qd, length, props) + added_mass_energy(
        q, qd, length, axis, props.hydro
    )
    both = ca.Function(
        "T", [q, qd, length], [reference, closed_form_kinetic_energy(q, qd, length, props)]
    )
    rng = np.random.default_rng(5)
    worst = 0.0
    for _ in range(8):
        expected, closed = both(rng.normal(size=5) * 2, rng.normal(size=5), rng.uniform(1, 30))
        worst = max(worst, abs(float(closed) / float(expected) - 1))
    validation("closed-form 5-DOF energy with added mass (C_at != C_a)", "second formulation",
               "trace form + 2-point Gauss added mass", "max relative difference",
               f"{worst:.1e}", "<= 1e-12")  # fmt: skip
    assert worst <= 1e-12


@pytest.mark.parametrize("submerged", [False, True], ids=["air", "water"])
def test_translational_mass_of_hanging_chain(models_dir, submerged):
    """Sum over elements of the x-x (and z-z) mass entries at the hanging state.

    In air both are rho A L. In water the elements are vertical, so x is normal to them
    ((rho + C_a rho_w) A L) and z is axial ((rho + C_at rho_w) A L with C_at = 0). Exact up to
    round-off: 1e-12 relative. The element mass blocks are those the model uses
    (rfe.element_functions); the Hessian of model.energy w.r.t. the rates must be the same matrix.
    """
    scene = load_scene(models_dir / "hanging.toml", {"environment.submerged": submerged})
    model = CableModel.from_scene(scene)
    drive = Drive.from_scene(scene)
    x, u = equilibrium(model, drive).state, rest_inputs(drive)
    element, _ = element_functions(model.spec.element)
    q, qd = model.coordinates(x)
    blocks = [
        np.array(element(qi, qdi, li)[0])
        for qi, qdi, li in zip(q, qd, model.element_lengths(u[INPUTS.top_length]), strict=True)
    ]
    cable, hyd = scene.cable, scene.hydrodynamics
    water = scene.environment.water_density if submerged else 0.0
    area, length = cable.cross_section_area, cable.length
    normal = (cable.density + hyd.added_mass_normal * water) * area * length
    axial = (cable.density + hyd.added_mass_axial * water) * area * length
    assert sum(b[0, 0] for b in blocks) == pytest.approx(normal, rel=1e-12)
    assert sum(b[1, 1] for b in blocks) == pytest.approx(normal, rel=1e-12)
    assert sum(b[2, 2] for b in blocks) == pytest.approx(axial, rel=1e-12)

    size = model.state_size // 2
    rates = model.x[size:]
    hessian = ca.Function(
        "m", [model.x, model.u], [ca.hessian(model.energy(model.x, model.u), rates)[0]]
    )
    full = np.array(hessian(x, u))
    dofs = model.dofs
    for i, block in enumerate(blocks):
        sl = slice(i * dofs, (i + 1) * dofs)
        np.testing.assert_allclose(full[sl, sl], block, rtol=1e-12, atol=1e-9 * np.abs(block).max())


# ----------------------------------------------------------------------------------------------
def test_hanging_axis_and_rotation():
    """A hanging element (psi = pi/2, theta = 0) points up along z, from A_i to A_{i+1}: exact."""
    np.testing.assert_allclose(
        np.array(axis_direction(np.pi / 2, 0.0)).ravel(), [0.0, 0.0, 1.0], atol=1e-15
    )
    rng = np.random.default_rng(3)
    for psi, theta, phi in [(np.pi / 2, 0.0, 0.0), *rng.uniform(-3, 3, size=(5, 3))]:
        rotation = np.array(rotation_matrix(psi, theta, phi))
        axis = np.array(axis_direction(psi, theta)).ravel()
        expected = [np.cos(theta) * np.cos(psi), np.sin(theta), np.cos(theta) * np.sin(psi)]
        np.testing.assert_allclose(axis, expected, atol=1e-15)
        np.testing.assert_allclose(rotation[:, 0], axis, atol=1e-15)
        np.testing.assert_allclose(rotation.T @ rotation, np.eye(3), atol=1e-14)
        assert np.linalg.det(rotation) == pytest.approx(1.0, abs=1e-14)
        # Our R is the paper's R seen in our axes (x, y, z) = (X, -Z, Y).
        to_world = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])
        paper = _rz(psi) @ _ry(theta) @ _rx(phi)
        np.testing.assert_allclose(rotation, to_world @ paper, atol=1e-15)


# ----------------------------------------------------------------------------------------------
def test_jacobians(full_model, tilted):
    """Shapes of d xdot/dx and d xdot/du; columns against central differences, 1e-5 relative."""
    model = full_model(False)
    size = model.state_size
    jac_x, jac_u = model.jacobian("x"), model.jacobian("u")
    assert jac_x.sparsity_out(0).shape == (size, size)
    assert jac_u.sparsity_out(0).shape == (size, INPUT_SIZE)
    with pytest.raises(ValueError, match="wrt"):
        model.jacobian("t")

    rng = np.random.default_rng(7)
    u = np.zeros(INPUT_SIZE)
    u[INPUTS.top_length] = model.spec.segment_length / 2
    u[INPUTS.end_force] = [2e3, -1e3, -3e3]  # N
    x = tilted(model, u)
    x[size // 2 :] = 0.2 * rng.normal(size=size // 2)
    dense_x = np.array(jac_x(x, u))
    dense_u = np.array(jac_u(x, u))

    def rhs(state, inputs):
        return np.array(model.rhs(state, inputs)).ravel()

    names = model.state_names
    for name in ("x_0", "z_3", "psi_2", "theta_5", "d_psi_4", "d_theta_3", "d_y_6"):
        k = names.index(name)
        step = 1e-6 * max(1.0, abs(x[k]))
        plus, minus = x.copy(), x.copy()
        plus[k] += step
        minus[k] -= step
        fd = (rhs(plus, u) - rhs(minus, u)) / (2 * step)
        assert max_relative(dense_x[:, k], fd) < 1e-5, name
    # One input column too: the end force along x (linear in u, so FD is exact up to round-off).
    k = 12
    du = np.zeros(INPUT_SIZE)
    du[k] = 1.0
    fd = (rhs(x, u + du) - rhs(x, u - du)) / 2
    assert max_relative(dense_u[:, k], fd) < 1e-5


def test_singular_state_is_rejected(full_model, tilted):
    """An element along y (theta = pi/2) is on the singular set of the Euler chart."""
    model = full_model(False)
    u = np.zeros(INPUT_SIZE)
    u[INPUTS.top_length] = model.spec.segment_length / 2
    x = tilted(model, u)
    model.check_regular(x)  # regular: no error
    x[model.state_names.index("theta_2")] = np.pi / 2
    with pytest.raises(ValueError, match="singular"):
        model.check_regular(x)
    x[model.state_names.index("theta_2")] = -np.pi / 2
    with pytest.raises(ValueError, match="singular"):
        model.check_regular(x)


@TORSION
def test_state_names(full_model, torsion):
    model = full_model(torsion)
    names = model.state_names
    assert len(names) == model.state_size == 2 * model.dofs * (model.spec.elements + 1)
    assert len(set(names)) == len(names)
    assert "psi_0" in names and "d_theta_3" in names
    assert names[: model.dofs] == ["x_0", "y_0", "z_0", "psi_0", "theta_0", "phi_0"][: model.dofs]
    assert names[model.state_size // 2] == "d_x_0"
    assert ("phi_2" in names) == torsion


def test_models_are_built_once_per_spec_in_a_process(models_dir):
    scene = load_scene(models_dir / "hanging.toml")
    first = CableModel.from_scene(scene)
    assert CableModel.from_scene(scene) is first
    assert CableModel.from_scene(scene.updated({"model.elements": 12})) is not first
    assert CableModel.from_scene(scene, elements=4).spec.elements == 4
