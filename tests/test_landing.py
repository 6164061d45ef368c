"""The landing from a hover: the lowering objective of the one WinchProblem, open and closed loop.

References independent of the code under test: the smoothstep's own values and finite
differences of the reference, the submerged weight of the line and the load (the hover's top
tension in still water), the locked winch (which leaves the load at the hover), and every
constraint measured on the verified run by :func:`check_landing`, not by the solver.
"""

from __future__ import annotations

import numpy as np
import pytest
from conftest import MODELS
from test_lowering import HEAVING, lowering_scene

import cable_ocp as co
from cable_ocp.lowering.checks import check_landing
from cable_ocp.lowering.hold import LINE_TOLERANCE
from cable_ocp.lowering.landing import (
    ACCELERATION_SHARE,
    HOVER,
    PEAK_ACCELERATION,
    PEAK_SPEED,
    SPEED_SHARE,
    TENSION_SHARE,
    LandingResult,
    approach_time,
    heave_peaks,
    land,
    landing_scene,
    tension_acceleration,
)
from cable_ocp.result_files.dataset import fields_equal
from cable_ocp.simulation.landing_reference import reference_error
from cable_ocp.simulation.seabed import clearance, clearance_reference

STILL = {"environment.current_profile": []}


def start_height(scene) -> float:
    """The end's height above the seabed at t = 0 of a scene's locked run (m)."""
    run = co.simulate(scene)
    return float(clearance(scene.seabed, run.end[0], clearance_reference(scene.seabed, run.end[0])))


@pytest.fixture(scope="module")
def landing():
    """The 2 t load of test_lowering's scene at its hover, in a sheared current."""
    scene = lowering_scene(**{"environment.current_profile": [{"z": 0.0, "u": 0.5}]})
    return scene, landing_scene(scene)


def test_the_reference_leaves_the_hover_at_rest_and_lands_at_rest_on_the_target():
    scene = lowering_scene()
    landed = landing_scene(scene)
    # A relative seabed lies delta below the start: the end starts at e = 0, the target is
    # delta - HOVER below it.
    assert landed.seabed.clearance == pytest.approx(scene.lowering.height + HOVER, abs=1e-3)
    target = scene.lowering.height - landed.seabed.clearance
    land_time = landed.lowering.land_time
    t = np.linspace(0.0, landed.numerics.duration, 20_001)
    e = reference_error(landed, t, 0.0)
    assert e[0] == 0.0 and target == pytest.approx(-HOVER, abs=1e-3)
    assert np.allclose(e[t >= land_time], target, atol=1e-12)
    speed = np.gradient(e, t)
    assert abs(speed[0]) < 1e-6 and np.abs(speed[t >= land_time]).max() < 1e-6
    # The smoothstep's peak speed 1.875 H / T, at half time.
    assert np.abs(speed).max() == pytest.approx(PEAK_SPEED * HOVER / land_time, rel=1e-6)
    # Any other scene, the line scene included, has no reference.
    assert not reference_error(scene, t, 3.0).any()
    assert not reference_error(co.load_scene(MODELS / "paper_flat.toml"), t, 3.0).any()


def test_the_landing_scene_hangs_the_end_at_the_hover_within_the_winch_and_the_rope(landing):
    scene, landed = landing
    assert landed.winch.line is None and landed.lowering is not None
    assert start_height(landed) == pytest.approx(scene.lowering.height + HOVER, abs=LINE_TOLERANCE)
    assert landed.model.elements == scene.winch.line.mesh.starting_elements(landed.cable.length)
    # The approach: the reference's peaks within their shares of the winch, the hold after it.
    land_time = landed.lowering.land_time
    hold = scene.numerics.duration - scene.lowering.land_time
    assert land_time == approach_time(scene, HOVER, hold)
    radius = scene.winch.drum_radius
    assert PEAK_SPEED * HOVER / land_time <= SPEED_SHARE * scene.winch.rate_max * radius
    peak = PEAK_ACCELERATION * HOVER / land_time**2
    assert peak <= ACCELERATION_SHARE * scene.winch.acceleration_max * radius
    assert landed.numerics.duration == pytest.approx(land_time + hold)
    # The drum may pay the hover out and more.
    assert landed.winch.angle_max * radius > HOVER


def test_the_hovers_top_tension_is_the_submerged_weight_in_still_water(validation):
    scene = lowering_scene(**STILL)
    landed = landing_scene(scene)
    allowed, top = tension_acceleration(landed)
    gravity, water = scene.environment.gravity, scene.environment.water_density
    cable, payload = landed.cable, landed.end.payload
    rope = (cable.density - water) * cable.cross_section_area * cable.length * gravity
    load = (payload.mass - water * payload.volume) * gravity
    validation(
        f"2 t load hanging {landed.cable.length:.4g} m (n = {landed.model.elements}) in still "
        "water at the hover of a landing",
        "analytic",
        "submerged weight of the line and the load",
        "|T_top / weight - 1|",
        f"{abs(top / (rope + load) - 1):.1e}",
        "<= 1e-6",
    )
    assert top == pytest.approx(rope + load, rel=1e-6)
    mass = cable.density * cable.cross_section_area * cable.length
    mass += payload.mass + payload.added_mass * water * payload.volume
    room = min(top - scene.lowering.tension_min, scene.lowering.tension_max - top)
    assert allowed == pytest.approx(TENSION_SHARE * room / mass)


def mass_of(scene) -> float:
    """The line's mass, the payload's and its added mass (kg)."""
    cable, payload = scene.cable, scene.end.payload
    water = scene.environment.water_density
    line = cable.density * cable.cross_section_area * cable.length
    return line + payload.mass + payload.added_mass * water * payload.volume


def test_a_tension_limit_close_to_the_landed_tension_lengthens_the_approach():
    scene = lowering_scene(**STILL)
    normal = landing_scene(scene)
    _, top = tension_acceleration(normal)
    # The landed line is the hover's longer by HOVER: its static tension is higher by that
    # much rope's submerged weight; 500 N above it is the room left.
    water, cable = scene.environment.water_density, normal.cable
    weight = (cable.density - water) * cable.cross_section_area * scene.environment.gravity
    most = top + weight * HOVER + 500.0
    tight = landing_scene(scene.updated({"lowering.tension_max": most}))
    allowed, _ = tension_acceleration(tight, HOVER)
    assert allowed == pytest.approx(TENSION_SHARE * 500.0 / mass_of(tight), rel=1e-9)
    land_time = tight.lowering.land_time
    assert land_time > normal.lowering.land_time
    assert PEAK_ACCELERATION * HOVER / land_time**2 <= allowed
    assert tight.numerics.duration - land_time == pytest.approx(
        normal.numerics.duration - normal.lowering.land_time
    )
    # The drum keeps its own limit: a compensated heave moves the drum, not the load.
    assert tight.winch.acceleration_max == scene.winch.acceleration_max
    result = land(tight)
    assert result.success, result.status
    assert result.report.peak_tension <= most


def test_the_optimised_landing_lands_every_check_passed_on_the_scenes_own_model(
    landing, validation, tmp_path
):
    scene, landed = landing
    result = land(landed)
    assert result.success, result.status
    report = result.report
    assert abs(report.landing_error) < 0.1 * scene.lowering.height_tolerance
    assert abs(report.landing_speed) < scene.lowering.landing_speed
    assert result.result.solver == "gauss-newton"
    # A calm: no heave to compensate (the top joint's bond residual is no heave).
    assert np.isnan(result.compensation_ratio) and "compensation" not in result.status
    assert "every check passed" in result.status
    # Verified on the scene's own model (its n), the run's error the reference's deviation.
    run = result.result.trajectory
    assert run.states.shape[1] == co.CableModel.from_scene(landed).state_size
    assert result.result.omega < 0.05
    # The baseline: the winch locked leaves the load at the hover.
    locked = check_landing(co.simulate(landed), None)
    assert locked.landing_error == pytest.approx(HOVER, abs=0.05)
    assert not locked.passed
    # IPOPT on the same transcription finds the same landing.
    other = land(landed, solver="ipopt")
    validation(
        f"2 t load landed from a {HOVER:g} m hover ({landed.cable.length:.4g} m of line, n = "
        f"{landed.model.elements}, sheared current), optimised on a reduced model, verified on "
        "the scene's own",
        "second formulation",
        "IPOPT on the same transcription; check_landing on the run",
        "landing error, speed (Gauss-Newton); |difference| of IPOPT's landing error",
        f"{report.landing_error:+.1e} m, {report.landing_speed:+.1e} m/s; "
        f"{abs(other.report.landing_error - report.landing_error):.1e} m",
        "< 1 cm, < 0.1 m/s; <= 2 mm",
    )
    assert other.success, other.status
    assert other.report.landing_error == pytest.approx(report.landing_error, abs=2e-3)
    # The paper's method on the same problem (its Omega is the deviation from the reference).
    searched = land(landed, solver="nelder-mead")
    assert searched.success, searched.status
    # Saved, loaded and replayed: the same run.
    result.result.save(tmp_path / "landing")
    saved = co.load_result(tmp_path / "landing")
    replayed = co.simulate(saved.scene, winch=saved)
    assert replayed.omega == pytest.approx(result.result.omega, abs=1e-9)
    # The landing itself, saved and loaded (issue 41): its optimum, report and scene restored.
    loaded = co.load_result(result.save(tmp_path / "landed.nc"))
    assert isinstance(loaded, LandingResult) and loaded.status == result.status
    assert fields_equal(loaded.report, result.report) and not loaded.closed_loop
    replayed = co.simulate(loaded.scene, winch=loaded.result)
    assert replayed.omega == pytest.approx(result.result.omega, abs=1e-9)


def test_the_closed_loop_lands_and_holds_against_the_heave(tmp_path):
    scene = lowering_scene(**HEAVING)
    result = land(scene, closed_loop=True)
    # Saved and loaded (issue 41): the closed loop's result read back by its kind.
    loaded = co.load_result(result.save(tmp_path / "looped.nc"))
    assert isinstance(loaded.result, co.MpcResult) and loaded.closed_loop
    assert loaded.status == result.status and fields_equal(loaded.report, result.report)
    # The approach leaves the drum its heave's peaks over the landing and the hold.
    landed = result.scene
    speed, acceleration = heave_peaks(landed, landed.numerics.duration)
    radius, land_time = landed.winch.drum_radius, landed.lowering.land_time
    assert PEAK_SPEED * HOVER / land_time + speed <= landed.winch.rate_max * radius
    peak = PEAK_ACCELERATION * HOVER / land_time**2
    assert peak + acceleration <= landed.winch.acceleration_max * radius
    assert result.success, result.status
    report = result.report
    assert abs(report.landing_error) < scene.lowering.height_tolerance
    assert abs(report.landing_speed) < scene.lowering.landing_speed
    assert report.hold_deviation < scene.lowering.hold_band
    assert result.compensation_ratio > 90.0
    # The same sea with the winch locked: the load rides the heave at the hover.
    locked = co.simulate(result.scene)
    after = locked.time >= result.scene.lowering.land_time
    assert np.std(locked.end[after, 2]) > 0.8 * np.std(locked.top[after, 2])


def test_a_landing_that_its_drum_cannot_hold_fails_with_its_reason():
    scene = lowering_scene(**{**HEAVING, "winch.acceleration_max": 0.3})
    result = land(scene, closed_loop=True)
    assert not result.success
    # The plant's drum holds its limit (it saturates, and says so): the load cannot follow.
    assert "the drum saturated" in result.status


def test_a_landing_refuses_bad_input_before_any_work():
    scene = lowering_scene()
    with pytest.raises(ValueError, match="hover = -1.0 m is out of range"):
        landing_scene(scene, hover=-1.0)
    with pytest.raises(ValueError, match="hover = 150.0 m is out of range: .* rigid rod"):
        landing_scene(scene, hover=150.0)
    with pytest.raises(ValueError, match="top.motion = 'tow'"):
        landing_scene(lowering_scene(**{"top.motion": "tow"}))
    with pytest.raises(ValueError, match="leaves no hold"):
        landing_scene(lowering_scene(**{"numerics.duration": 200.0}))
    with pytest.raises(ValueError, match="from a hover by co.land"):
        co.optimize(scene)  # a line paid out by elements: the message points to the landing
    with pytest.raises(ValueError, match="no \\[lowering\\] table"):
        land(co.load_scene(MODELS / "paper_flat.toml"))


def test_a_hover_beyond_the_landing_line_is_refused_naming_hover_and_its_range():
    """Not blamed on the landing scene's cable.length or winch.angle_min (issue 45, item 8)."""
    scene = lowering_scene()
    for hover in (400.0, 214.0):  # beyond the 215 m landing line, and just inside it
        with pytest.raises(ValueError) as caught:
            landing_scene(scene, hover=hover)
        message = str(caught.value)
        assert message.startswith(f"hover = {hover} m is out of range: must be > 0 and <= about")
        assert "cable.length" not in message and "angle_min" not in message


def test_a_step_that_does_not_divide_a_second_still_gives_a_landing_on_whole_steps():
    """The approach (whole seconds) is rounded up to whole steps (issue 45, item 8: co.land)."""
    scene = lowering_scene(**{"numerics.step": 0.03, "numerics.duration": 230.1,
                              "lowering.land_time": 200.1})  # fmt: skip
    landed = landing_scene(scene)
    for duration in (landed.lowering.land_time, landed.numerics.duration):
        steps = duration / 0.03
        assert abs(steps - round(steps)) < 1e-6, duration
    assert landed.numerics.duration - landed.lowering.land_time == pytest.approx(30.0)


@pytest.mark.slow
def test_deploy_lands_from_its_hover_optimised_by_both_solvers_and_by_the_closed_loop():
    """The bundled deploy scene, from 10 m above its target: 1005 m of line, H_s = 2 m."""
    scene = co.load_scene(MODELS / "deploy.toml")
    landed = landing_scene(scene)
    lowering = landed.lowering
    for solver in ("gauss-newton", "ipopt"):
        result = land(landed, solver=solver)
        assert result.success, result.status
        report = result.report
        assert abs(report.landing_error) < lowering.height_tolerance
        assert abs(report.landing_speed) < lowering.landing_speed
        assert lowering.tension_min < report.least_tension < report.peak_tension
        assert report.peak_tension < lowering.tension_max
        print(result.status, f"{result.result.wall_time:.1f} s")
    looped = land(landed, closed_loop=True)
    assert looped.success, looped.status
    assert looped.report.hold_deviation < lowering.hold_band
    assert looped.compensation_ratio > 90.0
    print(looped.status, f"real-time factor {looped.result.real_time_factor:.0f}")


def test_the_fitted_step_keeps_the_landing_on_a_step():
    """The control nodes' step fit also ends a step at lowering.land_time (the lowering bench's
    case 4 of seed 0 raised when a fitted step of 82/1680 s missed its landing at 22 s)."""
    from cable_ocp.control.defaults import on_nodes
    from cable_ocp.scene.schema import whole_steps

    scene = co.load_scene(
        MODELS / "deep_lift.toml",
        {"numerics.duration": 82.0, "numerics.step": 0.05, "numerics.output_every": 10,
         "seabed.clearance": 10.0,
         "lowering": {"land_time": 22.0, "height": 5.0, "tension_min": 6e4,
                      "tension_max": 9e5}},
    )  # fmt: skip
    fitted, note = on_nodes(scene, 16)
    step = fitted.numerics.step
    assert step <= 0.05 and "control nodes" in note
    assert whole_steps(82.0, step) is not None and whole_steps(22.0, step) is not None
    steps = whole_steps(82.0, step)
    assert steps % 16 == 0 and steps % 10 == 0  # the nodes and the samples on step ends too
