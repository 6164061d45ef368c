"""RK4 runs against physics: energy balance, rest, blow-up detection, order of convergence."""

from __future__ import annotations

import numpy as np
import pytest

from cable_ocp.drive.drive import Drive
from cable_ocp.model.cable import CableModel
from cable_ocp.scene.schema import load_scene
from cable_ocp.simulation.integrate import (
    RK4_STAGES,
    WHOLE_STEP_LIMIT,
    SimulationError,
    extrapolated_rhs_size,
    integrate,
    reference_solution,
    step_count,
    whole_step_fits,
)
from cable_ocp.simulation.statics import equilibrium, rest_inputs


def build(models_dir, overrides=None):
    scene = load_scene(models_dir / "hanging.toml", overrides)
    model = CableModel.from_scene(scene)
    drive = Drive.from_scene(scene)
    return scene, model, drive, rest_inputs(drive)


def positions(model: CableModel, states: np.ndarray) -> np.ndarray:
    """Element positions (k, n+1, 3) of states (k, state_size)."""
    q = states[:, : model.state_size // 2].reshape(len(states), model.element_count, model.dofs)
    return q[:, :, :3]


@pytest.fixture(scope="module")
def in_water(models_dir):
    """hanging.toml as it is: in water, n = 10, top fixed, with its equilibrium."""
    scene, model, drive, u = build(models_dir)
    return scene, model, drive, u, equilibrium(model, drive).state


# ----------------------------------------------------------------------------------------------
def test_energy_conserved_in_air(models_dir, tilted, validation):
    """No dissipation (in air, so no drag; bending_damping = 0): energy stays constant.

    Straight line tilted by psi = pi/2 + 0.3, theta = 0.1, released from rest, n = 10, h = 0.01 s,
    20 s, default Baumgarte gains. max |E - E0| / (E0 - E_eq) <= 1e-6, with E_eq the energy of
    the hanging equilibrium; bond residual <= 1e-8 m.
    """
    scene, model, drive, u = build(models_dir, {"environment.submerged": False})
    assert model.spec.element.hydro is None and model.spec.bending_damping == 0.0
    assert model.spec.elements == 10
    x0 = tilted(model, u)
    x_eq = equilibrium(model, drive).state
    run = integrate(model, x0, drive, 20.0, 0.01, tolerance=1e-6)
    count = len(run.time)
    assert count == 2001 and run.time[-1] == pytest.approx(20.0)
    energy = np.array(model.energy.map(count)(run.states.T, run.inputs.T)).ravel()
    released = energy[0] - float(model.energy(x_eq, u))
    assert released > 1e5  # J: the tilt releases a real amount of energy
    drift = np.abs(energy - energy[0]).max() / released
    residual = model.outputs.map(count)(x=run.states.T, u=run.inputs.T)["bond_residual"]
    residual = np.array(residual)
    validation("energy in air, no dissipation, n = 10, 20 s, h = 0.01 s", "conservation",
               "E(t) = E(0)", "max |E - E0| / released energy; bond residual",
               f"{drift:.1e}; {np.abs(residual).max():.1e} m", "<= 1e-6; <= 1e-8 m")  # fmt: skip
    assert drift <= 1e-6
    assert np.abs(residual).max() <= 1e-8  # m
    # The cable really swings: the end moves by metres.
    assert (
        np.abs(positions(model, run.states)[:, 0] - positions(model, run.states)[0, 0]).max() > 10
    )


def test_hanging_at_rest_stays_at_rest(in_water, validation):
    """From the equilibrium in water (n = 10, h = 0.05 s, 100 s): max |r(t) - r(0)| <= 1e-9 m."""
    _, model, drive, _, x_eq = in_water
    run = integrate(model, x_eq, drive, 100.0, 0.05)
    assert len(run.time) == 2001
    drift = np.abs(positions(model, run.states) - positions(model, x_eq[None, :])).max()
    validation("hanging at rest in water, n = 10, 100 s, h = 0.05 s", "conservation",
               "exact rest", "max |r(t) - r(0)|", f"{drift:.1e} m", "<= 1e-9 m")  # fmt: skip
    assert drift <= 1e-9


def perturbed(model, u, chained, seed: int = 0) -> np.ndarray:
    """The hanging chain with every element tilted by ~0.01 rad (bonds exact), at rest."""
    rng = np.random.default_rng(seed)
    count = model.element_count
    return chained(
        model, u, np.pi / 2 + 0.01 * rng.normal(size=count), 0.01 * rng.normal(size=count)
    )


def test_unstable_step_raises_non_finite(in_water, chained):
    """h = 5 s, far above the stability limit: the state overflows and the run stops with a remedy.

    The bond check is disabled (tolerance = inf) so that the non-finite check is what fires.
    """
    _, model, drive, u, _ = in_water
    x0 = perturbed(model, u, chained)
    with pytest.raises(SimulationError) as info:
        integrate(model, x0, drive, 100.0, 5.0, tolerance=np.inf)
    message = str(info.value)
    assert "non-finite" in message
    assert "t =" in message and "step" in message and "h = 5 s" in message
    assert "smaller numerics.step" in message


def test_unstable_step_raises_bond_residual(in_water, chained):
    """The same run with the default tolerance stops at the first step, on the bond residual."""
    _, model, drive, u, _ = in_water
    x0 = perturbed(model, u, chained)
    with pytest.raises(SimulationError) as info:
        integrate(model, x0, drive, 100.0, 5.0)
    message = str(info.value)
    assert "bond residual" in message and "t = 5 s" in message
    assert "t =" in message and "step" in message
    assert "smaller numerics.step" in message


def test_step_count_rejects_non_dividing_step():
    assert step_count(100.0, 0.05) == 2000
    assert step_count(0.3, 0.1) == 3
    with pytest.raises(ValueError, match=r"numerics\.step"):
        step_count(1.0, 0.3)
    with pytest.raises(ValueError, match=r"numerics\.step"):
        step_count(0.01, 0.02)


def test_integrate_rejects_non_dividing_step(in_water):
    _, model, drive, _, x_eq = in_water
    with pytest.raises(ValueError, match=r"numerics\.step"):
        integrate(model, x_eq, drive, 1.0, 0.3)


def test_rk4_fourth_order_against_dop853(models_dir, tilted, validation):
    """RK4 vs DOP853 (rtol = atol = 1e-10): in-water tilted release, n = 5, 2 s.

    Error of the final state at h = 0.02 s over h = 0.01 s must exceed 10 (4th order: 16).
    """
    _, model, drive, u = build(models_dir, {"model.elements": 5})
    x0 = tilted(model, u)
    reference = reference_solution(model, x0, drive, np.array([0.0, 2.0]))[-1]
    assert np.abs(reference - x0).max() > 1.0  # it moves
    errors = [
        np.abs(integrate(model, x0, drive, 2.0, h).states[-1] - reference).max()
        for h in (0.02, 0.01)
    ]
    validation("RK4 order, tilted release in water, n = 5, 2 s", "converged reference",
               "DOP853, rtol = atol = 1e-10",
               "final-state error at h = 0.01 s; ratio h = 0.02 / 0.01",
               f"{errors[1]:.1e}; {errors[0] / errors[1]:.1f}",
               "< 1e-7; > 10 (4th order: 16)")  # fmt: skip
    assert errors[1] < 1e-7
    assert errors[0] / errors[1] > 10, errors


def test_energy_conserved_in_water_with_anisotropic_added_mass(models_dir, tilted, validation):
    """Drag off in water: added mass (C_a = 1, C_at = 0) and a payload store no energy.

    The added-mass terms come from the water's kinetic energy (CONVENTIONS.md §4), so cable plus
    entrained water conserve energy: max |E - E0| / (E0 - E_eq) <= 1e-6 over 20 s at h = 0.01 s.
    """
    overrides = {
        "hydrodynamics.drag": False,
        "end.payload.mass": 2000.0,
        "end.payload.volume": 0.5,
    }
    scene, model, drive, u = build(models_dir, overrides)
    assert scene.hydrodynamics.added_mass_axial == 0.0
    x0 = tilted(model, u)
    run = integrate(model, x0, drive, 20.0, 0.01, tolerance=1e-6)
    energy = np.array(model.energy.map(len(run.time))(run.states.T, run.inputs.T)).ravel()
    released = energy[0] - float(model.energy(equilibrium(model, drive).state, u))
    drift = np.abs(energy - energy[0]).max() / released
    validation("energy in water, added mass C_a = 1, C_at = 0, payload, no drag, 20 s",
               "conservation", "E(t) = E(0) (cable + entrained water)",
               "max |E - E0| / released energy", f"{drift:.1e}", "<= 1e-6")  # fmt: skip
    assert drift <= 1e-6


def test_torsional_instability_is_caught(models_dir):
    """Beyond the torsion step limit (about 0.12 s / n) the twist explodes with the bonds intact
    and the state finite; the run must still stop, naming the twist and the remedy."""
    scene, model, drive, u = build(models_dir, {"model.torsion": True})
    x0 = equilibrium(model, drive).state
    twist = model.twist_angle_index()
    x0[twist] += 1e-6 * np.random.default_rng(1).normal(size=model.element_count)
    with pytest.raises(SimulationError, match="twisted apart") as info:
        integrate(model, x0, drive, 20.0, 0.1, tolerance=1.0)
    assert "smaller numerics.step" in str(info.value)


@pytest.mark.parametrize(
    "scene_name, overrides",
    [
        ("hanging.toml", {"model.elements": 9}),
        ("paper_hill.toml", {"model.elements": 12}),
        ("catenary.toml", {"model.elements": 8}),
        ("end_force.toml", {"model.elements": 7, "model.torsion": True}),
    ],
)
def test_rhs_size_extrapolated_from_small_models_is_exact(models_dir, scene_name, overrides):
    """The flat right-hand side grows by the same instructions per element (affine in n)."""
    parametric = CableModel.from_scene(load_scene(models_dir / scene_name, overrides)).parametric
    assert extrapolated_rhs_size(parametric) == parametric.rhs_size()


@pytest.mark.parametrize(
    "scene_name, overrides",
    [
        ("hanging.toml", {"model.elements": 6}),
        ("hanging.toml", {"model.elements": 30}),
        ("hanging.toml", {"model.elements": 20, "environment.submerged": False}),
        ("end_force.toml", {"model.elements": 4, "model.torsion": True}),
    ],
)
def test_whole_step_decision_is_that_of_the_eliminated_rhs(models_dir, scene_name, overrides):
    """The shortcut on the size before elimination decides as the eliminated size does."""
    model = CableModel.from_scene(load_scene(models_dir / scene_name, overrides))
    parametric = model.parametric
    eliminated = parametric.rhs.n_instructions()
    # Elimination removes far less than half of the instructions (17-20 %), never more.
    assert parametric.rhs_size() / 2 < eliminated <= parametric.rhs_size()
    assert whole_step_fits(parametric) == (RK4_STAGES * eliminated <= WHOLE_STEP_LIMIT)
