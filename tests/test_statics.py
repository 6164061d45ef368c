"""Static equilibria against analytic references: the catenary (paper §4.1), the hanging cable,
the cable trailing in a current; unphysical equilibria are refused (issue 9).

Newton's method on the element angles also converges to the straight cable mirrored through the top
(upstream and above it, every bond in compression): from the still-water string guess it did so
in strong currents. The string guess carries the current's drag, and every equilibrium is checked.
"""

from __future__ import annotations

import numpy as np
import pytest

from cable_ocp.drive.drive import Drive
from cable_ocp.model.cable import CableModel
from cable_ocp.model.layout import INPUTS
from cable_ocp.scene.schema import EndPayload, load_scene
from cable_ocp.simulation import statics
from cable_ocp.simulation.statics import (
    RESIDUAL_TOLERANCE,
    EquilibriumError,
    bond_tensions,
    equilibrium,
    rest_inputs,
)
from cable_ocp.studies.validation import CatenaryCheck, catenary_check


@pytest.fixture(scope="module")
def catenary(models_dir):
    """``n -> CatenaryCheck`` of catenary.toml at n elements, cached."""
    scene = load_scene(models_dir / "catenary.toml")
    cache = {}

    def get(elements: int) -> CatenaryCheck:
        if elements not in cache:
            cache[elements] = catenary_check(scene, elements)
        return cache[elements]

    return get


def test_catenary_scene_is_the_papers(models_dir):
    """catenary.toml holds the paper's data: A = 0.07^2/4 m^2, H = 20 kN, V = 50 kN, in air."""
    scene = load_scene(models_dir / "catenary.toml")
    assert scene.cable.cross_section_area == pytest.approx(0.07**2 / 4, rel=1e-15)
    assert (scene.end.force[0], scene.end.force[2]) == (20000.0, 50000.0)
    assert not scene.environment.submerged


def test_catenary_elastic_error_n15(catenary, validation):
    """eps_x, eps_z <= 0.1 % against the elastic catenary, EA = E A (paper: < 0.5 %)."""
    check = catenary(15)
    eps_x, eps_z = 100 * check.max_error_x, 100 * check.max_error_z
    validation("catenary statics, n = 15 (paper 4.1)", "analytic", "elastic catenary eq. 34",
               "eps_x, eps_z", f"{eps_x:.3f} %, {eps_z:.3f} %",
               "<= 0.1 % (paper: < 0.5 %)")  # fmt: skip
    assert eps_x <= 0.1, eps_x
    assert eps_z <= 0.1, eps_z


def test_catenary_inextensible_error_converges_second_order(catenary, validation):
    """max(eps_x, eps_z) against the inextensible catenary falls strictly with n = 5, 15, 30, 60.

    Second order: each doubling of n must cut the error by more than 3 (15 -> 30 and 30 -> 60).
    """
    ns = (5, 15, 30, 60)
    error = {n: 100 * catenary(n).max_error_inextensible for n in ns}
    validation("catenary convergence in n", "analytic", "inextensible catenary",
               "max(eps_x, eps_z) at n = 5, 15, 30, 60",
               ", ".join(f"{error[n]:.2g}" for n in ns) + " %",
               "falls; ratio > 3 per doubling; < 0.01 % at n = 15")  # fmt: skip
    for coarse, fine in zip(ns, ns[1:], strict=False):
        assert error[fine] < error[coarse], error
    assert error[15] / error[30] > 3, error
    assert error[30] / error[60] > 3, error
    assert error[15] < 0.01, error  # %


def test_catenary_tensions(catenary, validation):
    """Every bond force equals T(s) of eq. 34c at its joint A_1..A_{n+1}, 1e-9 relative.

    A rigid chain in equilibrium carries exactly the end load less the weight below each joint; at
    the pin (s = 0) that is T(0) = hypot(H, V - w L).
    """
    check = catenary(15)
    validation("catenary bond tensions, n = 15", "analytic", "T(s) eq. 34c",
               "largest relative error over the n + 1 bonds", f"{check.tension_error:.1e}",
               "<= 1e-9")  # fmt: skip
    assert check.tension_error <= 1e-9


def test_catenary_check_refuses_bad_element_counts(models_dir):
    scene = load_scene(models_dir / "catenary.toml")
    with pytest.raises(ValueError, match=r"^elements = 0: must be an integer from 1 to 1000$"):
        catenary_check(scene, 0)


# ----------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def hanging_case(models_dir):
    """``torsion -> (scene, model, equilibrium state, rest inputs)`` for hanging.toml, cached."""
    cache = {}

    def get(torsion: bool):
        if torsion not in cache:
            scene = load_scene(models_dir / "hanging.toml", {"model.torsion": torsion})
            model = CableModel.from_scene(scene)
            drive = Drive.from_scene(scene)
            cache[torsion] = scene, model, equilibrium(model, drive).state, rest_inputs(drive)
        return cache[torsion]

    return get


TORSION = pytest.mark.parametrize("torsion", [False, True], ids=["5dof", "6dof"])


@TORSION
def test_hanging_top_tension_is_submerged_weight(hanging_case, torsion, validation):
    """Top tension = (rho - rho_w) A g L to 1e-6 relative; each bond carries the weight below it."""
    scene, model, x, u = hanging_case(torsion)
    cable, env = scene.cable, scene.environment
    per_length = (cable.density - env.water_density) * cable.cross_section_area * env.gravity
    tensions = model.output_values(x, u)["tensions"].ravel()
    validation(f"hanging in water, top tension, {model.dofs} DOF", "analytic",
               "submerged weight (rho - rho_w) A g L", "relative error",
               f"{abs(tensions[-1] / (per_length * cable.length) - 1):.1e}", "<= 1e-6")  # fmt: skip
    assert tensions[-1] == pytest.approx(per_length * cable.length, rel=1e-6)
    lengths = np.array([float(v) for v in model.element_lengths(u[INPUTS.top_length])])
    np.testing.assert_allclose(tensions, per_length * np.cumsum(lengths), rtol=1e-6)


@TORSION
def test_hanging_elements_are_vertical(hanging_case, torsion):
    """Every element hangs straight down: |e_x|, |e_y| < 1e-12, joints on the z axis (1e-9 m)."""
    _, model, x, u = hanging_case(torsion)
    q, qd = model.coordinates(x)
    psi = np.array([qi[3] for qi in q])
    theta = np.array([qi[4] for qi in q])
    e = np.stack([np.cos(theta) * np.cos(psi), np.sin(theta), np.cos(theta) * np.sin(psi)])
    assert np.abs(e[:2]).max() < 1e-12
    np.testing.assert_allclose(e[2], 1.0, atol=1e-12)
    np.testing.assert_array_equal(np.concatenate(qd), 0.0)
    out = model.output_values(x, u)
    joints = out["joints"]
    assert np.abs(joints[:2]).max() < 1e-9  # m
    assert joints[2, 0] == pytest.approx(-model.spec.cable_length, abs=1e-9)
    assert np.abs(out["bond_residual"]).max() < 1e-12  # bonds hold (m)


def test_hanging_torsion_variant_same_equilibrium(hanging_case):
    """The 6-DOF model finds the 5-DOF equilibrium: same positions and angles (1e-9), no twist."""
    _, model6, x6, _ = hanging_case(True)
    _, model5, x5, _ = hanging_case(False)
    q6, _ = model6.coordinates(x6)
    q5, _ = model5.coordinates(x5)
    np.testing.assert_allclose(np.stack(q6)[:, :5], np.stack(q5), rtol=0, atol=1e-9)
    assert np.abs(x6[model6.twist_angle_index()]).max() < 1e-9


def test_compiled_equilibrium_matches_the_symbolic_one(models_dir, validation):
    """Newton on the compiled structured rhs (FD Jacobian) vs CasADi's Newton on the SX rhs."""
    scene = load_scene(models_dir / "hanging.toml", {"environment.current": [0.4, -0.2, 0.05]})
    model = CableModel.from_scene(scene)
    drive = Drive.from_scene(scene)
    compiled = equilibrium(model, drive, compiled=True).state
    symbolic = equilibrium(model, drive).state
    difference = float(np.abs(compiled - symbolic).max())
    validation("hanging in a current, n = 10, compiled statics", "second formulation",
               "CasADi Newton on the symbolic equations", "max state difference",
               f"{difference:.1e} m", "<= 1e-7 m")  # fmt: skip
    assert difference <= 1e-7


# ----------------------------------------------------------------------------------------------
# In a current.
# Up to the 10 m/s that a scene accepts (the fastest tidal streams).
CURRENTS = [(0.0, v, 0.0) for v in (1.0, 2.0, 5.0, 10.0)] + [(5.0, 0.0, 0.0), (3.0, 4.0, 0.0)]


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
    ``L (w sin a + 1/2 rho_w pi d C_dt V^2 cos^2 a)`` (1e-8 relative). The end's error is largest
    in weak currents, from the smoothed |v| of the model's drag.
    """
    scene, model, drive, u = in_current(models_dir, current)
    x = equilibrium(model, drive).state
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
        ((0.0, 9.0, 0.0), {"end.payload.mass": 5000.0, "end.payload.volume": 1.0,
                            "end.payload.drag_area": 2.0}),
    ],
    ids=["10m/s", "x-current+end-force", "upstream-end-force", "payload"],
)  # fmt: skip
def test_top_force_balances_weight_drag_and_end_loads(models_dir, current, overrides, validation):
    """The force at the top equals the weight in water less the drag and the end loads (1e-8 rel).

    The drag is summed in numpy over the equilibrium's elements (Morison at the current velocity,
    the scene's coefficients); the end force and the payload's weight and drag are added by hand.
    """
    scene, model, drive, u = in_current(models_dir, current, **overrides)
    x = equilibrium(model, drive, compiled=True).state
    out = model.output_values(x, u)
    joints, top_force = out["joints"], out["bond_forces"][:, -1]
    env, end = scene.environment, scene.end
    velocity = np.array(current)
    weight = (scene.cable.density - env.water_density) * scene.cable.cross_section_area
    payload = end.payload or EndPayload(mass=0.0)
    weight = weight * scene.cable.length + payload.mass - env.water_density * payload.volume
    payload_drag = 0.5 * env.water_density * payload.drag * payload.drag_area
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


def test_compiled_newton_line_search_at_n100(models_dir, validation):
    """end_force.toml (n = 100, 3 kN down at the end) in 10 m/s: the compiled Newton converges.

    Bending curves the free end away from the string guess; at n = 100 full Newton steps wander,
    halved ones converge. The top force balances the weight, the numpy drag and the end force to
    1e-8 of the load, and the end trails more than 250 m downstream and 50 m below the top.
    """
    scene = load_scene(models_dir / "end_force.toml", {"environment.current": [0.0, 10.0, 0.0]})
    model = CableModel.from_scene(scene)
    drive = Drive.from_scene(scene)
    u = rest_inputs(drive)
    assert model.spec.elements == 100
    x = equilibrium(model, drive, compiled=True).state
    out = model.output_values(x, u)
    joints, top_force = out["joints"], out["bond_forces"][:, -1]
    env = scene.environment
    weight = (scene.cable.density - env.water_density) * scene.cable.cross_section_area
    loads = (
        np.array([0.0, 0.0, -weight * scene.cable.length * env.gravity])
        + morison_drag(scene, joints).sum(axis=1)
        + np.array(scene.end.force)
    )
    error = float(np.abs(loads - top_force).max() / np.linalg.norm(loads))
    end = joints[:, 0] - joints[:, -1]
    validation("top force in a current of 10 m/s, n = 100, 3 kN down at the end", "conservation",
               "numpy sum of weight, Morison drag and end force",
               "relative force imbalance; end offset downstream, below the top",
               f"{error:.1e}; {end[1]:.1f} m, {-end[2]:.1f} m",
               "<= 1e-8; > 250 m, > 50 m")  # fmt: skip
    assert error <= 1e-8
    assert bond_tensions(model, x, u).min() > 0
    assert end[1] > 250 and end[2] < -50  # m: trailing downstream


def test_string_guess_is_the_straight_cable_in_a_current(models_dir):
    """With no end load the drag-aware string guess is already the equilibrium (1e-6 rad)."""
    _, model, drive, u = in_current(models_dir, (0.0, 5.0, 0.0))
    x = equilibrium(model, drive).state
    q, _ = model.coordinates(x)
    angles = np.array([qi[3:5] for qi in q])
    np.testing.assert_allclose(statics.string_guess(model, u), angles, rtol=0, atol=1e-6)


def test_compiled_equilibrium_in_a_strong_current_matches_the_symbolic_one(models_dir):
    """At 10 m/s both Newton's methods find the same trailing state (1e-7)."""
    _, model, drive, _ = in_current(models_dir, (0.0, 10.0, 0.0))
    compiled = equilibrium(model, drive, compiled=True).state
    symbolic = equilibrium(model, drive).state
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
    monkeypatch.setattr(statics, "signed_tensions", lambda joints, forces: np.ones(11))
    with pytest.raises(EquilibriumError, match=r"free end is 136 m above the top .* not physical"):
        equilibrium(model, drive, guess=hanging_straight_down(model))


def test_weaker_current_equilibrium_is_a_good_guess(models_dir):
    """The remedy the error suggests works: the 2 m/s equilibrium leads Newton to the 10 m/s one."""
    _, weak, weak_drive, _ = in_current(models_dir, (0.0, 2.0, 0.0))
    _, model, drive, u = in_current(models_dir, (0.0, 10.0, 0.0))
    x = equilibrium(model, drive, guess=equilibrium(weak, weak_drive)).state  # a guess object
    assert float(np.abs(x - equilibrium(model, drive).state).max()) <= 1e-7
    assert bond_tensions(model, x, u).min() > 0


def test_equilibrium_reports_its_shape_and_pulling_tensions(models_dir):
    """Hanging straight down, the bond forces lie along the elements: the signed tensions equal
    the bond-force norms (1e-9 relative) and the end hangs a cable length below the top (1 mm)."""
    scene = load_scene(models_dir / "hanging.toml")
    model = CableModel.from_scene(scene)
    found = equilibrium(model, Drive.from_scene(scene))
    norms = model.output_values(found.state, found.inputs)["tensions"].ravel()
    np.testing.assert_allclose(found.tensions, norms, rtol=1e-9)
    drop = found.joints[2, -1] - found.end[2]
    assert drop == pytest.approx(scene.cable.length, abs=1e-3)
    assert found.residual <= RESIDUAL_TOLERANCE
