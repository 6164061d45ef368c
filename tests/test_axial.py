"""The elastic rope (cable_ocp.model.axial): statics, period, damping, energy, and the auto rule.

References are independent of the model: the vertical elastic catenary (the paper's eq. 34 with
the stretch ``T / EA`` integrated along the line), the spring-mass period of DNV-RP-H103 §5.2, the
logarithmic decrement of a damped oscillator, the energy balance without dissipation, and the
assembled sparse KKT solve beside the bordered block Thomas elimination.
"""

import math

import casadi as ca
import numpy as np
import pytest
from conftest import MODELS

import cable_ocp as co
from cable_ocp.drive.drive import Drive
from cable_ocp.model.cable import CableModel, spec_from_scene
from cable_ocp.model.parameters import parameter_names
from cable_ocp.scene.axial_choice import RIGID_ERROR, axial_choice, axial_period
from cable_ocp.scene.schema import SceneError
from cable_ocp.simulation.statics import equilibrium
from cable_ocp.studies.validation import catenary_check

PAYLOAD = 40000.0  # kg

# A 300 m steel line with a 40 t mass at its end, in air, no damping: a pure spring and mass.
IN_AIR = {
    "environment.submerged": False,
    "environment.water_density": 0.0,
    "model.axial": "elastic",
    "cable.axial_damping": 0.0,
    "end.payload.mass": PAYLOAD,
}


def _scene(overrides: dict, payload: float = PAYLOAD):
    return co.load_scene(MODELS / "hanging.toml", {**overrides, "end.payload.mass": payload})


def _free_run(model: CableModel, start: np.ndarray, u: np.ndarray, step: float, steps: int):
    """RK4 from ``start`` with the inputs held: the states (state_size, steps)."""
    x = ca.MX.sym("x", model.state_size)
    k1 = model.rhs(x, u)
    k2 = model.rhs(x + step / 2 * k1, u)
    k3 = model.rhs(x + step / 2 * k2, u)
    k4 = model.rhs(x + step * k3, u)
    advance = ca.Function("advance", [x], [x + step / 6 * (k1 + 2 * k2 + 2 * k3 + k4)])
    return np.array(advance.mapaccum(steps)(start))


def _released(overrides: dict):
    """The elastic model, and its state hanging a 1.5x heavier load (released at t = 0)."""
    scene = _scene(overrides)
    model = CableModel.from_scene(scene)
    heavier = CableModel.from_scene(_scene(overrides, 1.5 * PAYLOAD))
    start = equilibrium(heavier, Drive.from_scene(scene)).state
    inputs = equilibrium(model, Drive.from_scene(scene)).inputs
    return scene, model, start, inputs


def _crossings(signal: np.ndarray, step: float) -> np.ndarray:
    centred = signal - signal.mean()
    k = np.where((centred[:-1] < 0) & (centred[1:] >= 0))[0]
    return (k + -centred[k] / (centred[k + 1] - centred[k])) * step


def test_statics_stretch_is_the_vertical_elastic_catenary(validation):
    """Hanging in water with its payload: the end lies (W L + w' L^2 / 2) / EA below L (0.5 %)."""
    scene = co.load_scene(MODELS / "deep_lift.toml")
    model = CableModel.from_scene(scene)
    assert model.axial == 1
    found = equilibrium(model, Drive.from_scene(scene))
    cable, payload, water = scene.cable, scene.end.payload, scene.environment.water_density
    line_weight = (cable.density - water) * cable.cross_section_area * 9.81
    payload_weight = (payload.mass - water * payload.volume) * 9.81
    length = cable.length
    stretch = (payload_weight * length + line_weight * length**2 / 2) / cable.axial_stiffness_value
    model_stretch = -found.end[2] - length
    error = abs(model_stretch / stretch - 1)
    validation("deep_lift statics: 40 t on 2000 m of 40 mm steel, EA = 126 MN, n = 20, in water",
               "analytic", "vertical elastic catenary (eq. 34): (W L + w' L^2 / 2) / EA",
               "stretch of the line (relative error)",
               f"{model_stretch:.4f} m against {stretch:.4f} m ({error:.1e})",
               "<= 0.5 %")  # fmt: skip
    assert stretch > 1.0  # metres: the test would not notice a rigid rope otherwise
    assert model_stretch == pytest.approx(stretch, rel=5e-3)
    top_tension = payload_weight + line_weight * length
    assert found.tensions[-1] == pytest.approx(top_tension, rel=1e-6)


def test_free_period_and_damping_match_the_spring_and_mass(validation):
    """Released in air: T0 = 2 pi sqrt((M + m L / 3) / (EA / L)) within 0.5 %, zeta from decay."""
    zeta = 0.05
    scene, model, start, u = _released({**IN_AIR, "cable.axial_damping": zeta})
    period = axial_period(scene, scene.cable.length)
    step = period / 100
    states = _free_run(model, start, u, step, 800)
    strain = states[model.state_size // 2 - 1]
    measured = np.diff(_crossings(strain, step))
    damped = period / math.sqrt(1 - zeta**2)
    rest = equilibrium(model, Drive.from_scene(scene)).state[model.state_size // 2 - 1]
    peaks = [np.max(np.abs(strain[k : k + 100] - rest)) for k in range(0, 700, 100)]
    decrement = np.log(peaks[0] / peaks[-1]) / (len(peaks) - 1)
    validation("40 t on 300 m of 70 mm steel in air, released from 60 t, zeta = 0.05, n = 10",
               "analytic", "spring and mass: T0 sqrt(1 - zeta^2), T0 = 2 pi sqrt((M + m L/3) L/EA)",
               "free period (relative error); damping ratio from the decrement",
               f"{measured.mean():.5f} s against {damped:.5f} s "
               f"({abs(measured.mean() / damped - 1):.1e}); {decrement / (2 * math.pi):.4f}",
               "<= 0.5 %; 0.05 +- 10 %")  # fmt: skip
    assert measured.mean() == pytest.approx(damped, rel=5e-3)
    assert decrement / (2 * math.pi) == pytest.approx(zeta, rel=0.1)


def test_energy_with_the_elastic_energy_is_conserved_over_100_periods(validation):
    """In air, no damping: kinetic + gravity + strain energy drifts by < 1e-6 relative."""
    scene, model, start, u = _released(IN_AIR)
    period = axial_period(scene, scene.cable.length)
    steps_per_period = 200
    states = _free_run(model, start, u, period / steps_per_period, 100 * steps_per_period)
    count = states.shape[1]
    energy = np.array(model.energy.map(count)(states, np.tile(u[:, None], count)))
    initial = float(model.energy(start, u))
    drift = np.max(np.abs(energy - initial))
    # The oscillation's own energy, 1/2 EA L s_a^2, drifts by far less than itself too.
    strain = states[model.state_size // 2 - 1]
    amplitude = (strain.max() - strain.min()) / 2
    oscillation = 0.5 * scene.cable.axial_stiffness_value * scene.cable.length * amplitude**2
    validation("40 t on 300 m of steel in air, no damping, 100 axial periods, h = T0 / 200",
               "conservation", "kinetic + gravity + elastic energy is constant",
               "largest drift relative to the total; to the oscillation's energy",
               f"{drift / abs(initial):.1e}; {drift / oscillation:.1e}",
               "< 1e-6; < 1e-4")  # fmt: skip
    assert drift / abs(initial) < 1e-6
    assert drift / oscillation < 1e-4


def test_bordered_thomas_solve_equals_the_sparse_kkt_solve(validation):
    """At a moving state of the elastic model the two eliminations agree to rounding."""
    scene = co.load_scene(MODELS / "deep_lift.toml", {"model.elements": 6})
    model = CableModel.from_scene(scene)
    found = equilibrium(model, Drive.from_scene(scene))
    state = found.state.copy()
    half = model.state_size // 2
    state[half:] = 0.05 * np.random.default_rng(44).standard_normal(half)
    thomas = np.array(model.rhs(state, found.inputs)).ravel()
    sparse = np.array(model.rhs_sparse(state, found.inputs)[0]).ravel()
    error = np.max(np.abs(thomas - sparse)) / np.max(np.abs(thomas))
    validation("deep_lift, n = 6, elastic, random velocities", "second formulation",
               "assembled sparse KKT solve (csparse) with the strain's border",
               "largest difference in x' relative to its largest entry", f"{error:.1e}",
               "<= 1e-9")  # fmt: skip
    assert error <= 1e-9


def test_the_elastic_rope_meets_the_inclined_elastic_catenary(validation):
    """The paper's catenary (H = 20 kN, V = 50 kN, in air) with the elastic rope, n = 60."""
    scene = co.load_scene(MODELS / "catenary.toml", {"model.axial": "elastic"})
    elastic = catenary_check(scene, 60)
    rigid = catenary_check(co.load_scene(MODELS / "catenary.toml"), 60)
    error = 100 * max(elastic.max_error_x, elastic.max_error_z)
    rigid_error = 100 * max(rigid.max_error_x, rigid.max_error_z)
    validation("catenary statics with the elastic rope, n = 60 (paper 4.1)", "analytic",
               "elastic catenary eq. 34", "max(eps_x, eps_z); the rigid rope's",
               f"{error:.4f} %; {rigid_error:.4f} %",
               "<= 0.015 % and below a third of the rigid rope's")  # fmt: skip
    assert error <= 0.015
    assert error < rigid_error / 3


def test_auto_keeps_the_paper_rope_rigid_and_its_parameters_unchanged():
    """Scenes whose axial period is far below their excitation keep the rigid model exactly."""
    for name in ("paper_hill", "small_tow", "survey", "hanging", "catenary", "end_force"):
        scene = co.load_scene(MODELS / f"{name}.toml")
        choice = axial_choice(scene)
        assert not choice.elastic and choice.rigid_error <= RIGID_ERROR, name
        spec = spec_from_scene(scene)
        assert spec.axial_stiffness == 0.0
        assert not {"axial_stiffness", "axial_damping"} & set(parameter_names(spec))
        assert CableModel.from_scene(scene).axial == 0


def test_auto_chooses_the_elastic_rope_where_the_waves_reach_its_period():
    choice = axial_choice(co.load_scene(MODELS / "deep_lift.toml"))
    assert choice.elastic and choice.rigid_error > RIGID_ERROR
    assert choice.period == pytest.approx(5.7, abs=0.1)
    assert "elastic rope" in choice.note and "T0 = 5.7" in choice.note
    rigid = co.load_scene(MODELS / "deep_lift.toml", {"model.axial": "rigid"})
    assert CableModel.from_scene(rigid).axial == 0


def test_an_elastic_line_paid_out_stretches_as_its_weight_says(validation):
    """A 5 t payload on 40 mm steel paid out at 0.2 m/s from 100 m in still water, elastic.

    Quasi-static: the end lies the line out plus its elastic stretch (W L + w' L^2 / 2) / EA
    below the top, as splits add elements and EA / L falls with the line out.
    """
    from test_payout import ramped_pay_out

    scene = co.load_scene(
        MODELS / "deep_lift.toml",
        {
            "cable.length": 100.0,
            "numerics.duration": 400.0,
            "numerics.step": 0.05,
            "numerics.output_every": 10,
            "model.axial": "elastic",
            "top.heave": None,
            "winch.angle_max": 80.0,
            "winch.line": {"element_length": 20.0, "pay_out_max": 80.0},
        },
    )
    radius = scene.winch.drum_radius
    run = co.simulate(scene, winch=ramped_pay_out(0.2, 10.0, radius), compiled=True)
    line = scene.cable.length + radius * (run.winch_angle - run.winch_angle[0])
    cable, payload, water = scene.cable, scene.end.payload, scene.environment.water_density
    line_weight = (cable.density - water) * cable.cross_section_area * 9.81
    payload_weight = (payload.mass - water * payload.volume) * 9.81
    stretch = (payload_weight * line + line_weight * line**2 / 2) / cable.axial_stiffness_value
    settled = run.time > 60.0
    error = run.end[:, 2] - (run.top[:, 2] - line - stretch)
    worst = float(np.abs(error[settled]).max())
    validation("40 t on 40 mm steel paid out at 0.2 m/s from 100 m to 180 m, 20 m elements, "
               f"still water, elastic ({len(run.segments)} segments), after 60 s", "analytic",
               "z_top - L_out(t) - (W L + w' L^2 / 2) / EA", "end depth error; the stretch",
               f"{worst:.1e} m; {stretch[-1]:.3f} m", "< 2 % of the stretch")  # fmt: skip
    assert len(run.segments) >= 4
    assert worst < 0.02 * stretch[-1]


def test_an_elastic_run_saves_and_loads_its_strain(tmp_path):
    """The strain and its rate are variables of the run's file; the states come back exactly."""
    scene = co.load_scene(MODELS / "deep_lift.toml", {"numerics.duration": 4.0})
    run = co.simulate(scene, compiled=True)
    data = run.to_xarray()
    assert data["axial_strain"].attrs["units"] == "1"
    assert data["axial_strain"].values[0] == pytest.approx(6.7681 / 2000.0, rel=1e-3)
    loaded = type(run).load(run.save(tmp_path / "deep"))
    assert np.array_equal(loaded.states, run.states)
    assert loaded.state_names == run.state_names and run.state_names[-1] == "d_strain"


def test_compiled_statics_of_an_elastic_rope_in_a_current_converge():
    """The robustness bench's seed-0 case 10 (66 mm synthetic rope, 547 m, a sheared current):
    the compiled Newton stalled on the strain (0.03 rad/s^2 left); its equilibrium is the exact
    Newton's, and the rigid rope's end 8 cm higher by the line's stretch."""
    from cable_ocp.studies.scene_space import PLACED, space_cases

    case = space_cases(50, 0)[10]
    given = {k: v for k, v in case.items() if k != PLACED}
    scene = co.load_scene(MODELS / "paper_hill.toml", {**given, "seabed.hills": []})
    model = CableModel.from_scene(scene)
    assert model.axial == 1
    compiled = equilibrium(model, Drive.from_scene(scene), compiled=True)
    exact = equilibrium(model, Drive.from_scene(scene))
    assert np.allclose(compiled.end, exact.end, atol=1e-9)
    rigid = equilibrium(CableModel.from_scene(scene.updated({"model.axial": "rigid"})),
                        Drive.from_scene(scene))  # fmt: skip
    assert 0.05 < rigid.end[2] - exact.end[2] < 0.12


@pytest.mark.parametrize(
    ("overrides", "field"),
    [
        ({"cable.axial_stiffness": 1e5}, "cable.axial_stiffness"),
        ({"cable.fill_factor": 0.1, "end.payload.mass": 4e5}, "cable.fill_factor"),
    ],
)
def test_a_rope_that_would_hang_stretched_beyond_any_rope_is_refused(overrides, field):
    """Issue 45's fault injection: EA = 1e5 N left the end 10.5 km down, 'success'."""
    scene = co.load_scene(MODELS / "deep_lift.toml", overrides)
    with pytest.raises(SceneError, match=rf"{field}: EA = .* by .* % .*at most 10 %"):
        CableModel.from_scene(scene)
    rigid = scene.updated({"model.axial": "rigid"})  # the rigid rope has no use for EA
    assert CableModel.from_scene(rigid).axial == 0


def test_structured_loops_equal_the_flat_elastic_right_hand_side(validation):
    """The compiled path's loops (model/axial_structured.py) against the flat SX equations."""
    from cable_ocp.model import structured

    scene = co.load_scene(MODELS / "deep_lift.toml", {"model.elements": 6})
    model = CableModel.from_scene(scene)
    found = equilibrium(model, Drive.from_scene(scene))
    state, inputs = found.state.copy(), found.inputs.copy()
    half = model.state_size // 2
    state[half:] = 0.05 * np.random.default_rng(7).standard_normal(half)
    inputs[9:12] = [found.inputs[9], 0.3, 0.7]  # the winch paying out and accelerating
    inputs[6:9] = [0.1, 0.2, 0.5]  # the top accelerating
    flat = np.array(model.rhs(state, inputs)).ravel()
    loops = structured.structured_rhs(model.parametric)(state, inputs, model.parameters)
    error = np.max(np.abs(np.array(loops).ravel() - flat)) / np.max(np.abs(flat))
    validation("deep_lift, n = 6, elastic, moving state, winch and top accelerating",
               "second formulation", "the flat SX right-hand side (model/axial.py)",
               "largest difference in x' relative to its largest entry", f"{error:.1e}",
               "<= 1e-12")  # fmt: skip
    assert error <= 1e-12
