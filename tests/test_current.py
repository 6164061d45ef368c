"""The current as a function of depth (issue 16 item 2): a table z -> (u, v) in the drag.

References: a uniform table against the uniform current (bitwise); a two-layer table's drag on a
straight element against the Gauss sum done by hand; the equilibrium in a two-layer current against
the weight and the drag summed in numpy over its elements.
"""

from __future__ import annotations

import dataclasses

import casadi as ca
import numpy as np
import pytest

from cable_ocp.drive.drive import Drive
from cable_ocp.model.cable import CableModel, spec_from_scene
from cable_ocp.model.current import current_at, current_values
from cable_ocp.model.hydro import HydroCoefficients
from cable_ocp.model.rfe import element_functions
from cable_ocp.scene.schema import SceneError, load_scene
from cable_ocp.simulation.run import simulate
from cable_ocp.simulation.statics import bond_tensions, equilibrium, rest_inputs

# Two layers: 0.6 m/s (with 0.2 m/s across) above z = -40 m, 0.1 m/s (-0.1 across) below -60 m.
TWO_LAYERS = [
    {"z": 0.0, "u": 0.6, "v": 0.2},
    {"z": -40.0, "u": 0.6, "v": 0.2},
    {"z": -60.0, "u": 0.1, "v": -0.1},
    {"z": -300.0, "u": 0.1, "v": -0.1},
]
PAYLOAD = {"mass": 500.0, "volume": 0.05, "drag_area": 0.5}


def layered(z: float) -> np.ndarray:
    """The TWO_LAYERS current at the height z (m), by hand: (u, v, 0), m/s."""
    if z >= -40.0:
        return np.array([0.6, 0.2, 0.0])
    if z <= -60.0:
        return np.array([0.1, -0.1, 0.0])
    s = (-40.0 - z) / 20.0
    return np.array([0.6 + s * (0.1 - 0.6), 0.2 + s * (-0.1 - 0.2), 0.0])


@pytest.mark.parametrize("compiled", [False, True], ids=["interpreted", "compiled"])
def test_a_uniform_table_is_bitwise_the_uniform_current(models_dir, compiled, validation):
    """small_tow with a payload: a three-row table of one current against that uniform current."""
    rows = [{"z": z, "u": 0.3, "v": -0.1} for z in (0.0, -40.0, -400.0)]
    uniform = load_scene(
        models_dir / "small_tow.toml",
        {"environment.current": [0.3, -0.1, 0.0], "end.payload": PAYLOAD},
    )
    table = load_scene(
        models_dir / "small_tow.toml",
        {"environment.current_profile": rows, "end.payload": PAYLOAD},
    )
    # The same model: so also the compiled n = 100 step (built with FMA contraction) agrees.
    assert CableModel.from_scene(table).parametric is CableModel.from_scene(uniform).parametric
    a = simulate(uniform, compiled=compiled, quiet=True)
    b = simulate(table, compiled=compiled, quiet=True)
    differ = int(np.count_nonzero(a.states != b.states))
    validation(f"small_tow, uniform current table, {'compiled' if compiled else 'interpreted'}",
               "second formulation", "the same uniform current as environment.current",
               "state entries that differ over 40 s", str(differ), "0 (bitwise)")  # fmt: skip
    assert a.states.shape == b.states.shape
    assert np.array_equal(a.states, b.states)
    assert np.array_equal(a.inputs, b.inputs)


def test_two_layer_drag_on_a_straight_element(models_dir, validation):
    """A vertical element at rest from z = -70 to -30 m across the layers' transition.

    Its generalised drag force is ``sum_k w_k J_k^T f(c(z_k))`` over the three Gauss points
    (``xi = 20 (1 + x_k)`` m, ``x_k = 0, +-sqrt(3/5)``, weights ``20 (8/9, 5/9, 5/9)`` m) with
    ``f = 1/2 rho_w d C_dn |c| c`` (the whole current is across the element; |c| smoothed by
    1e-4 m/s as the model does). For the vertical axis ``dr/dpsi = -xi e_x``, ``dr/dtheta =
    xi e_y``. Done by hand here; the model's to 1e-12 relative.
    """
    scene = load_scene(models_dir / "hanging.toml", {"environment.current_profile": TWO_LAYERS})
    props = dataclasses.replace(spec_from_scene(scene).element, submerged_weight_per_length=0.0)
    element, _ = element_functions(props)
    q = np.array([0.0, 0.0, -70.0, np.pi / 2, 0.0])
    force = np.array(element(q, np.zeros(5), 40.0)[1]).ravel()

    env, hyd = scene.environment, scene.hydrodynamics
    half_rho_d_cdn = 0.5 * env.water_density * scene.cable.diameter * hyd.drag_normal
    root = np.sqrt(3 / 5)
    expected = np.zeros(5)
    for x, w in ((-root, 5 / 9), (0.0, 8 / 9), (root, 5 / 9)):
        xi, weight = 20.0 * (1 + x), 20.0 * w
        c = layered(-70.0 + xi)
        f = half_rho_d_cdn * np.sqrt(c @ c + 1e-8) * c
        expected += weight * np.array([f[0], f[1], f[2], -xi * f[0], xi * f[1]])
    error = float(np.abs(force - expected).max() / np.abs(expected).max())
    validation("two-layer current on a vertical element across the layers", "analytic",
               "Gauss sum by hand at the points' currents", "relative difference",
               f"{error:.1e}", "<= 1e-12")  # fmt: skip
    assert error <= 1e-12
    # The layers do matter: the surface current alone gives another force.
    surface = half_rho_d_cdn * np.sqrt(0.6**2 + 0.2**2 + 1e-8) * 0.6 * 40.0
    assert abs(force[0] - surface) > 0.3 * surface


def test_equilibrium_in_two_layers_balances_weight_and_drag(models_dir, validation):
    """hanging.toml with a payload in TWO_LAYERS: the top force equals the loads (1e-8 relative).

    The loads are the weight in water of the cable and the payload, the payload's drag at the
    end's depth and each element's Morison drag summed by 8-point Gauss quadrature in numpy at
    the equilibrium's joints (the model uses 3 points: the sum differs by the quadrature error
    across the layers' kinks, bounded here by 1e-3 of the load).
    """
    scene = load_scene(
        models_dir / "hanging.toml",
        {"environment.current_profile": TWO_LAYERS, "end.payload": PAYLOAD},
    )
    model, drive = CableModel.from_scene(scene), Drive.from_scene(scene)
    u = rest_inputs(drive)
    x = equilibrium(model, drive).state
    out = model.output_values(x, u)
    joints, top_force = out["joints"], out["bond_forces"][:, -1]
    env, cable, hyd, payload = scene.environment, scene.cable, scene.hydrodynamics, PAYLOAD
    half_rho_d = 0.5 * env.water_density * cable.diameter
    nodes, weights = np.polynomial.legendre.leggauss(8)
    drag = np.zeros(3)
    for lower, upper in zip(joints.T[:-1], joints.T[1:], strict=True):
        span = upper - lower
        length = np.linalg.norm(span)
        axis = span / length
        for node, weight in zip(nodes, weights, strict=True):
            c = layered(lower[2] + 0.5 * (1 + node) * span[2])
            along = (c @ axis) * axis
            across = c - along
            per_length = half_rho_d * (
                hyd.drag_normal * np.linalg.norm(across) * across
                + np.pi * hyd.drag_axial * np.linalg.norm(along) * along
            )
            drag += 0.5 * length * weight * per_length
    end_current = layered(joints[2, 0])
    wet = (cable.density - env.water_density) * cable.cross_section_area * cable.length
    wet += payload["mass"] - env.water_density * payload["volume"]
    loads = np.array([0.0, 0.0, -wet * env.gravity]) + drag
    payload_drag = 0.5 * env.water_density * payload["drag_area"]
    loads += payload_drag * np.linalg.norm(end_current) * end_current
    error = float(np.abs(-top_force + loads).max() / np.linalg.norm(loads))
    validation("hanging with a payload in a two-layer current, n = 10", "conservation",
               "numpy sum of weight and Morison drag (8-point Gauss) at the equilibrium",
               "relative force imbalance", f"{error:.1e}", "<= 1e-3")  # fmt: skip
    assert bond_tensions(model, x, u).min() > 0
    assert joints[2, 0] < -200.0  # the end hangs in the lower layer
    assert error <= 1e-3
    assert joints[0, 0] - joints[0, -1] > 0  # downstream


def test_the_profile_is_a_parameter_of_one_structure(models_dir):
    """Two tables of four rows share one symbolic model; the rows are entries of p (v = 0 too)."""
    scene = load_scene(models_dir / "hanging.toml", {"environment.current_profile": TWO_LAYERS})
    weaker = [dict(row, u=row["u"] / 2, v=0.0) for row in TWO_LAYERS]
    other = scene.updated({"environment.current_profile": weaker})
    assert CableModel.from_scene(other).parametric is CableModel.from_scene(scene).parametric
    names = CableModel.from_scene(scene).parameter_names
    assert "element.hydro.current_z[3]" in names and "element.hydro.current_v[0]" in names


@pytest.mark.parametrize(
    "profile, extra, message",
    [
        ([{"z": 0.0, "u": 0.5}, {"z": -10.0}, {"z": -5.0}], {},
         r"^environment\.current_profile\[2\]\.z = -5\.0 is out of range: must be < "
         r"environment\.current_profile\[1\]\.z = -10\.0"),
        ([{"z": 0.0}, {"z": 0.0}], {}, r"^environment\.current_profile\[1\]\.z = 0\.0 is out"),
        ([{"z": 5.0, "u": 0.1}], {}, r"^environment\.current_profile\[0\]\.z = 5\.0 is out of "
         r"range: must be <= 0 \(m\)"),
        ([{"z": -1.0, "u": float("nan")}], {},
         r"^environment\.current_profile\[0\]\.u = nan is out of range: must be finite"),
        ([{"z": -1.0, "u": float("inf")}], {}, r"^environment\.current_profile\[0\]\.u = inf"),
        ([{"u": 0.3}], {}, r"^environment\.current_profile\[0\]\.z: missing required key"),
        ([{"z": -1.0, "w": 0.3}], {}, r"^environment\.current_profile\[0\]\.w: unknown key"),
        ([[0.0, 0.5, 0.0]], {}, r"^environment\.current_profile\[0\]: expected a table"),
        ([{"z": 0.0, "u": 0.3}], {"environment.current": [0.2, 0.0, 0.0]},
         r"^environment\.current = \[0\.2, 0\.0, 0\.0\]: give a uniform current or "
         r"environment\.current_profile, not both"),
    ],
    ids=["not-monotone", "repeated", "above-surface", "nan", "inf", "no-z", "unknown", "list",
         "both"],
)  # fmt: skip
def test_bad_profiles_are_one_line_errors(models_dir, profile, extra, message):
    overrides = {"environment.current_profile": profile, **extra}
    with pytest.raises(SceneError, match=message) as caught:
        load_scene(models_dir / "hanging.toml", overrides)
    assert "\n" not in str(caught.value)


def test_current_at_matches_its_numpy_twin():
    """The model's CasADi interpolation and the statics' numpy one agree (1e-15 m/s)."""
    hydro = HydroCoefficients(
        1025.0, 0.07, 0.004, 1.0, 0.1, 1.0, 0.0, (0.0, 0.0, 0.0), 3,
        tuple(r["z"] for r in TWO_LAYERS), tuple(r["u"] for r in TWO_LAYERS),
        tuple(r["v"] for r in TWO_LAYERS),
    )  # fmt: skip
    z = ca.SX.sym("z")
    at = ca.Function("c", [z], [current_at(hydro, z)])
    heights = np.array([5.0, 0.0, -20.0, -40.0, -45.0, -50.0, -59.9, -60.0, -100.0, -400.0])
    symbolic = np.hstack([np.array(at(h)) for h in heights]).T
    by_hand = np.array([layered(h) for h in heights])
    np.testing.assert_allclose(symbolic, by_hand, rtol=0, atol=1e-15)
    np.testing.assert_allclose(current_values(hydro, heights), by_hand, rtol=0, atol=1e-15)
