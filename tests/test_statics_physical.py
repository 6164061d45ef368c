"""Static equilibria in a current are the trailing shape, and unphysical ones are refused (issue 9).

Newton's method on the element angles also converges to the straight cable mirrored through the top
(upstream and above it, every bond in compression): from the still-water string guess it did so
at 5 and 10 m/s. The string guess now carries the current's drag, and every equilibrium is checked.
"""

from __future__ import annotations

import numpy as np
import pytest

from cable_ocp import statics
from cable_ocp.drive import Drive
from cable_ocp.model import CableModel
from cable_ocp.scene import load_scene
from cable_ocp.statics import EquilibriumError, bond_tensions, equilibrium, rest_inputs

CURRENTS = [(0.0, v, 0.0) for v in (1.0, 2.0, 5.0, 10.0, 50.0)] + [(5.0, 0.0, 0.0), (3.0, 4.0, 0.0)]


def in_current(models_dir, current, **overrides):
    """hanging.toml (n = 10, no end load) in a uniform current: scene, model, drive, rest inputs."""
    scene = load_scene(
        models_dir / "hanging.toml", {"environment.current": list(current), **overrides}
    )
    model = CableModel.from_scene(scene)
    drive = Drive.from_scene(scene)
    return scene, model, drive, rest_inputs(drive)


def morison_drag(scene, joints: np.ndarray) -> np.ndarray:
    """Drag (3, n+1), N, of the water on each element at rest, from its end points (numpy).

    Per unit length ``1/2 rho_w d (C_dn |v_n| v_n + pi C_dt |v_t| v_t)`` with ``v`` the current,
    ``v_t`` its part along the element and ``v_n`` the rest (the convention of hydro.py), times
    the length.
    """
    cable, hyd = scene.cable, scene.hydrodynamics
    current = np.array(scene.environment.current, float)
    spans = np.diff(joints, axis=1)
    lengths = np.linalg.norm(spans, axis=0)
    axes = spans / lengths
    along = (current @ axes) * axes
    across = current[:, None] - along
    per_length = (
        0.5
        * scene.environment.water_density
        * cable.diameter
        * (
            hyd.drag_normal * np.linalg.norm(across, axis=0) * across
            + np.pi * hyd.drag_axial * np.linalg.norm(along, axis=0) * along
        )
    )
    return per_length * lengths


def straight_trailing_cable(scene, speed: float) -> tuple[float, float]:
    """Angle below the horizontal (rad) and top tension (N) of a cable trailing in a current.

    With no end load every element balances its own load, so the cable is a straight line whose
    weight across it equals the normal drag, ``w cos a = 1/2 rho_w d C_dn V^2 sin^2 a``; the top
    carries ``L (w sin a + 1/2 rho_w pi d C_dt V^2 cos^2 a)`` along it.
    """
    cable, env, hyd = scene.cable, scene.environment, scene.hydrodynamics
    weight = (cable.density - env.water_density) * cable.cross_section_area * env.gravity
    half_rho_d = 0.5 * env.water_density * cable.diameter
    normal = half_rho_d * hyd.drag_normal * speed**2
    cos_a = (-weight + np.sqrt(weight**2 + 4 * normal**2)) / (2 * normal)
    angle = np.arccos(cos_a)
    axial = half_rho_d * np.pi * hyd.drag_axial * speed**2 * cos_a**2
    return float(angle), float(cable.length * (weight * np.sin(angle) + axial))


@pytest.mark.parametrize("current", CURRENTS, ids=lambda c: "current=" + ",".join(map(str, c)))
def test_equilibrium_in_a_current_is_the_trailing_shape(models_dir, current, validation):
    """Every bond pulls, the end trails downstream below the top, on the analytic straight line.

    The end lies at ``L (cos a v/|v|, -sin a)`` from the top (1e-6 m) and the top tension is
    ``L (w sin a + 1/2 rho_w pi d C_dt V^2 cos^2 a)`` (1e-8 relative). Measured 6e-9 to 2.5e-7 m
    (largest at 1 m/s, from the smoothed |v| of the model's drag) and 4e-12 to 2e-10.
    """
    scene, model, drive, u = in_current(models_dir, current)
    x = equilibrium(model, drive)
    tensions = bond_tensions(model, x, u)
    joints = model.output_values(x, u)["joints"]
    end = joints[:, 0] - joints[:, -1]
    speed = float(np.linalg.norm(current))
    downstream = np.array(current) / speed
    angle, top_tension = straight_trailing_cable(scene, speed)
    expected_end = scene.cable.length * np.append(np.cos(angle) * downstream[:2], -np.sin(angle))
    error = float(np.abs(end - expected_end).max())
    validation(f"hanging in a current of {current} m/s, n = 10", "analytic",
               "straight trailing cable w cos a = 1/2 rho d C_dn V^2 sin^2 a",
               "end position error, top tension error",
               f"{error:.1e} m, {abs(tensions[-1] / top_tension - 1):.1e}",
               "<= 1e-6 m, <= 1e-8")  # fmt: skip
    assert tensions.min() > 0, tensions
    assert end[2] < 0  # m, below the top
    assert end @ np.append(downstream[:2], 0.0) > 0  # downstream
    assert error <= 1e-6, (end, expected_end)
    assert tensions[-1] == pytest.approx(top_tension, rel=1e-8)


@pytest.mark.parametrize(
    "current, overrides",
    [
        ((0.0, 10.0, 0.0), {}),
        ((4.0, 0.0, 0.0), {"end.force": [0.0, 5000.0, -20000.0]}),
        ((0.0, 8.0, 0.0), {"end.force": [0.0, -20000.0, 0.0]}),
        ((0.0, 20.0, 0.0), {"end.payload_mass": 5000.0, "end.payload_volume": 1.0,
                            "end.payload_drag_area": 2.0}),
    ],
    ids=["10m/s", "x-current+end-force", "upstream-end-force", "payload"],
)  # fmt: skip
def test_top_force_balances_weight_drag_and_end_loads(models_dir, current, overrides, validation):
    """The force at the top equals the weight in water less the drag and the end loads (1e-8 rel).

    The drag is summed in numpy over the equilibrium's elements (Morison at the current velocity,
    the scene's coefficients); the end force and the payload's weight and drag are added by hand.
    Measured 3e-11 to 5e-10 of the total load.
    """
    scene, model, drive, u = in_current(models_dir, current, **overrides)
    x = equilibrium(model, drive, compiled=True)
    out = model.outputs(x, u)
    joints, top_force = np.array(out[0]), np.array(out[4])[:, -1]
    env, end = scene.environment, scene.end
    velocity = np.array(current)
    weight = (scene.cable.density - env.water_density) * scene.cable.cross_section_area
    weight = weight * scene.cable.length + end.payload_mass - env.water_density * end.payload_volume
    payload_drag = 0.5 * env.water_density * end.payload_drag * end.payload_drag_area
    loads = (
        np.array([0.0, 0.0, -weight * env.gravity])
        + morison_drag(scene, joints).sum(axis=1)
        + payload_drag * np.linalg.norm(velocity) * velocity
        + np.array(end.force)
    )
    held = -top_force  # the top's pull on the cable
    error = float(np.abs(held + loads).max() / np.linalg.norm(loads))
    validation(f"top force in a current of {current} m/s, {overrides or 'no end load'}",
               "conservation", "numpy sum of weight, Morison drag and end loads",
               "relative force imbalance", f"{error:.1e}", "<= 1e-8")  # fmt: skip
    np.testing.assert_allclose(held[:2], -loads[:2], rtol=0, atol=1e-8 * np.linalg.norm(loads))
    assert error <= 1e-8
    assert bond_tensions(model, x, u).min() > 0
    assert joints[2, 0] < joints[2, -1]


def test_compiled_newton_line_search_at_n100(models_dir):
    """end_force.toml (n = 100, 3 kN down at the end) in 10 m/s: the compiled Newton converges.

    Bending curves the free end away from the string guess (0.11 rad at n = 40); at n = 100 full
    Newton steps wandered (residual ~3e3 rad/s^2 after 50 steps), halved ones converge. The
    top force balances the weight, the numpy drag and the end force to 1e-8 of the load.
    """
    scene = load_scene(models_dir / "end_force.toml", {"environment.current": [0.0, 10.0, 0.0]})
    model = CableModel.from_scene(scene)
    drive = Drive.from_scene(scene)
    u = rest_inputs(drive)
    assert model.spec.elements == 100
    x = equilibrium(model, drive, compiled=True)
    out = model.outputs(x, u)
    joints, top_force = np.array(out[0]), np.array(out[4])[:, -1]
    env = scene.environment
    weight = (scene.cable.density - env.water_density) * scene.cable.cross_section_area
    loads = (
        np.array([0.0, 0.0, -weight * scene.cable.length * env.gravity])
        + morison_drag(scene, joints).sum(axis=1)
        + np.array(scene.end.force)
    )
    assert np.abs(loads - top_force).max() <= 1e-8 * np.linalg.norm(loads)
    assert bond_tensions(model, x, u).min() > 0
    end = joints[:, 0] - joints[:, -1]
    assert end[1] > 250 and end[2] < -50  # m: trailing downstream (measured 290.7, -73.2)


def test_string_guess_is_the_straight_cable_in_a_current(models_dir):
    """With no end load the drag-aware string guess is already the equilibrium (1e-6 rad)."""
    _, model, drive, u = in_current(models_dir, (0.0, 5.0, 0.0))
    x = equilibrium(model, drive)
    q, _ = model.coordinates(x)
    angles = np.array([qi[3:5] for qi in q])
    np.testing.assert_allclose(statics.string_guess(model, u), angles, rtol=0, atol=1e-6)


def test_compiled_equilibrium_in_a_strong_current_matches_the_symbolic_one(models_dir):
    """At 10 m/s both Newton's methods find the same trailing state (1e-7)."""
    _, model, drive, _ = in_current(models_dir, (0.0, 10.0, 0.0))
    compiled = equilibrium(model, drive, compiled=True)
    symbolic = equilibrium(model, drive)
    assert float(np.abs(compiled - symbolic).max()) <= 1e-7


# ----------------------------------------------------------------------------------------------
def hanging_straight_down(model) -> np.ndarray:
    """The still-water string guess: every element vertical (psi = pi/2, theta = 0), at rest."""
    state = np.zeros(model.state_size)
    state[3 : model.state_size // 2 : model.dofs] = np.pi / 2
    return state


@pytest.mark.parametrize("compiled", [False, True], ids=["symbolic", "compiled"])
def test_compressed_root_is_refused(models_dir, compiled):
    """From the vertical guess at 5 m/s Newton converges to the mirrored cable: EquilibriumError.

    That root has every bond pushing (top bond -9.53e4 N) with the end 136 m above the top.
    """
    _, model, drive, _ = in_current(models_dir, (0.0, 5.0, 0.0))
    with pytest.raises(EquilibriumError) as error:
        equilibrium(model, drive, guess=hanging_straight_down(model), compiled=compiled)
    message = str(error.value)
    assert "bond 10 in compression (-9.53e+04 N; 11 of 11 bonds push)" in message
    assert "not physical" in message
    assert "guess" in message and "reduce the current" in message


def test_end_above_the_top_is_refused(models_dir, monkeypatch):
    """With the tension check fooled, a heavy cable whose end stands above the top still fails."""
    _, model, drive, _ = in_current(models_dir, (0.0, 5.0, 0.0))
    monkeypatch.setattr(statics, "_signed_tensions", lambda joints, forces: np.ones(11))
    with pytest.raises(EquilibriumError, match=r"free end is 136 m above the top .* not physical"):
        equilibrium(model, drive, guess=hanging_straight_down(model))


def test_weaker_current_equilibrium_is_a_good_guess(models_dir):
    """The remedy the error suggests works: the 2 m/s equilibrium leads Newton to the 10 m/s one."""
    _, weak, weak_drive, _ = in_current(models_dir, (0.0, 2.0, 0.0))
    _, model, drive, u = in_current(models_dir, (0.0, 10.0, 0.0))
    x = equilibrium(model, drive, guess=equilibrium(weak, weak_drive))
    assert float(np.abs(x - equilibrium(model, drive)).max()) <= 1e-7
    assert bond_tensions(model, x, u).min() > 0
