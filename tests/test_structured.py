"""The structured right-hand side (loops over element Functions) against the flat SX one."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from cable_ocp.model.cable import CableModel
from cable_ocp.model.layout import INPUTS
from cable_ocp.model.structured import (
    structured_bond_residual,
    structured_joints_and_forces,
    structured_outputs,
    structured_rhs,
    supports,
)
from cable_ocp.scene.schema import load_scene

# Every force on: drag with a current, anisotropic added mass, bending damping and a payload.
EVERYTHING = {
    "model.elements": 7,
    "environment.current": [0.4, -0.2, 0.05],
    "hydrodynamics.added_mass_axial": 0.3,
    "cable.bending_damping": 0.2,
    "end.payload.mass": 2000.0,
    "end.payload.volume": 0.5,
    "end.payload.drag_area": 0.3,
}


@pytest.fixture(scope="module")
def model(models_dir):
    return CableModel.from_scene(load_scene(models_dir / "hanging.toml", EVERYTHING))


def random_point(model, rng):
    x = rng.normal(size=model.state_size) * 0.3
    x[3 : model.state_size // 2 : model.dofs] += np.pi / 2  # near hanging, off the singular set
    u = rng.normal(size=15) * 2.0
    u[INPUTS.top_length] = 20.0  # m, top element
    u[INPUTS.end_force] *= 1e3  # N
    return x, u


def test_structured_rhs_equals_the_flat_one(model, validation):
    rhs = model.bind(structured_rhs(model.parametric))
    rng = np.random.default_rng(3)
    worst = 0.0
    for _ in range(5):
        x, u = random_point(model, rng)
        flat, looped = np.array(model.rhs(x, u)), np.array(rhs(x, u))
        worst = max(worst, float(np.abs(flat - looped).max() / np.abs(flat).max()))
    validation("structured right-hand side (compiled path), n = 7, every force on",
               "second formulation", "flat SX right-hand side", "max relative difference of x'",
               f"{worst:.1e}", "< 1e-12")  # fmt: skip
    assert worst < 1e-12


def test_structured_jacobian_equals_the_flat_one(model):
    rhs = model.bind(structured_rhs(model.parametric))
    x_sym = ca.MX.sym("x", model.state_size)
    x, u = random_point(model, np.random.default_rng(4))
    looped = ca.Function("j", [x_sym], [ca.jacobian(rhs(x_sym, u), x_sym)])(x)
    flat = model.jacobian("x")(x, u)
    scale = np.abs(np.array(flat)).max()
    assert np.abs(np.array(looped) - np.array(flat)).max() / scale < 1e-10


def test_structured_joints_and_tensions_equal_the_model_outputs(model):
    outputs = model.bind(structured_outputs(model.parametric))
    x, u = random_point(model, np.random.default_rng(6))
    joints, tensions = (np.array(v) for v in outputs(x, u))
    reference = model.output_values(x, u)
    np.testing.assert_allclose(joints, reference["joints"], rtol=0, atol=1e-12)
    np.testing.assert_allclose(tensions, reference["tensions"], rtol=1e-12)


def test_structured_bond_forces_and_residuals_equal_the_model_outputs(model):
    """What a compiled run's equilibrium and bond checks take instead of the flat outputs."""
    parametric = model.parametric
    x, u = random_point(model, np.random.default_rng(7))
    reference = model.output_values(x, u)
    values = structured_joints_and_forces(parametric)(x=x, u=u, p=model.parameters)
    np.testing.assert_allclose(np.array(values["joints"]), reference["joints"], rtol=0, atol=1e-12)
    forces = np.array(values["bond_forces"])
    scale = np.abs(reference["bond_forces"]).max()
    np.testing.assert_allclose(forces, reference["bond_forces"], rtol=0, atol=1e-12 * scale)
    residual = np.array(structured_bond_residual(parametric)(x, u, model.parameters))
    np.testing.assert_allclose(residual, reference["bond_residual"], rtol=0, atol=1e-12)


def test_torsion_is_not_supported(models_dir):
    torsion = CableModel.from_scene(
        load_scene(models_dir / "hanging.toml", {"model.torsion": True, "model.elements": 6})
    )
    assert not supports(torsion)
    with pytest.raises(ValueError, match="5-DOF"):
        structured_rhs(torsion.parametric)
