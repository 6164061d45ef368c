"""Lowering a load to the seabed: the reference descent and the checks of a landing run.

References independent of the code under test: the vertical drop of a rope in still water (the
end falls by what the drum pays out), finite differences of the descent's line out, the winch's
own limits, and runs broken on purpose (a short landing line, a haul-in after the landing, a
pushing end force, limits below what the run reaches), each of which must be reported by the
check it breaks and by no other.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from conftest import MODELS

import cable_ocp as co
from cable_ocp.lowering.checks import check_landing
from cable_ocp.lowering.descent import (
    LIMIT_SHARE,
    ReferenceDescent,
    landing_line,
    reference_descent,
)
from cable_ocp.model.layout import INPUTS
from cable_ocp.result_files.dataset import fields_equal
from cable_ocp.simulation.line_trajectory import LineTrajectory

START, DROP, HEIGHT = 20.0, 200.0, 5.0  # m: line out at the start, start above the seabed, target
RATE_MAX, ACCELERATION_MAX = 4.0, 1.0  # rad/s, rad/s^2 on a 0.5 m drum
LOWERING = {
    "top.motion": "fixed",
    "cable.length": START,
    "end.payload": {"mass": 2000.0, "volume": 0.256, "drag_area": 1.0},
    "winch.line": {"pay_out_max": 250.0, "element_length": 10.0},
    "winch.rate_max": RATE_MAX,
    "winch.acceleration_max": ACCELERATION_MAX,
    "seabed.clearance": DROP,
    "seabed.minimum_clearance": 4.9,
    "lowering": {"land_time": 200.0, "height": HEIGHT, "tension_min": 1e3, "tension_max": 1e5},
    "numerics.duration": 230.0,
    "numerics.step": 0.05,
    "numerics.output_every": 5,
}
SHEARED = [{"z": 0.0, "u": 0.5}, {"z": -300.0, "u": 0.1}]  # m, m/s


def lowering_scene(**overrides) -> co.Scene:
    return co.load_scene(MODELS / "paper_flat.toml", {**LOWERING, **overrides})


@pytest.fixture(scope="module")
def sheared():
    """A 2 t load lowered 195 m through a sheared current on its reference descent, and its run."""
    scene = lowering_scene(**{"environment.current_profile": SHEARED})
    descent = reference_descent(scene)
    return scene, descent, co.simulate(scene, winch=descent.angle)


def test_landing_line_in_still_water_is_the_vertical_drop(validation):
    # Inextensible and hanging straight down: the end falls by exactly what is paid out.
    scene = lowering_scene()
    error = abs(landing_line(scene) - (START + DROP - HEIGHT))
    validation(
        "landing line of a 2 t load on 10 m elements, still water, 200 m above a flat seabed",
        "analytic", "the vertical drop L_0 + delta - height = 215 m", "|landing line - drop|",
        f"{error:.1e} m", "<= 1e-6 m",
    )  # fmt: skip
    assert error <= 1e-6


def test_descent_line_out_rates_are_its_derivatives():
    descent = ReferenceDescent(20.0, 1000.0, 900.0, 100.0, 0.5)
    t = np.linspace(0.0, 950.0, 190_001)
    line, rate, acceleration = descent.line_out(t)
    dt = t[1] - t[0]
    assert line[0] == 20.0 and line[-1] == pytest.approx(1000.0, abs=1e-9)
    assert np.abs(np.gradient(line, dt) - rate).max() < 1e-6
    assert np.abs(np.gradient(rate, dt) - acceleration).max() < 1e-6
    assert rate.max() == pytest.approx(descent.cruise_rate, rel=1e-12)
    assert np.abs(acceleration).max() == pytest.approx(descent.peak_acceleration, rel=1e-6)
    # Arrives at rest and stays: rate and acceleration zero from the landing on.
    assert np.all(rate[t >= 900.0] == 0.0) and np.all(acceleration[t >= 900.0] == 0.0)


def test_descent_keeps_within_its_share_of_the_winch_limits(sheared):
    scene, descent, _ = sheared
    t = np.linspace(0.0, scene.numerics.duration, 20_001)
    _, rate, acceleration = descent.angle(t)
    assert np.abs(rate).max() <= LIMIT_SHARE * RATE_MAX * (1 + 1e-12)
    assert np.abs(acceleration).max() <= LIMIT_SHARE * ACCELERATION_MAX
    # The ramps are as long as the rate limit lets them be: the plateau at its share.
    assert np.abs(rate).max() == pytest.approx(LIMIT_SHARE * RATE_MAX, rel=1e-9)


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        ({"lowering.land_time": 40.0}, "lowering.land_time = 40.0 s is out of range"),
        ({"winch.acceleration_max": 0.01, "winch.rate_max": None}, "winch.acceleration_max"),
        ({"lowering.height": -100.0}, "lowering.height"),
        ({"winch.line": {"pay_out_max": 100.0, "element_length": 10.0}}, "winch.line.pay_out_max"),
    ],
)
def test_an_impossible_descent_is_refused_naming_the_field(overrides, message):
    with pytest.raises(ValueError, match=message.replace(".", r"\.")):
        reference_descent(lowering_scene(**overrides))


def test_reference_descent_lands_and_passes_every_check(sheared, validation):
    scene, descent, run = sheared
    assert isinstance(run, LineTrajectory) and run.element_count.max() > run.element_count[0]
    report = check_landing(run, descent.angle)
    assert report.passed, str(report)
    names = {check.name for check in report.checks}
    assert names == {
        "landing height error", "landing speed", "hold band", "top tension min",
        "top tension max", "no slack bond", "drum rate", "drum acceleration", "minimum clearance",
        "slack criterion (DNV-RP-H103)", "seabed slope", "footprint clearance",
    }  # fmt: skip
    # The static landing line lands the dynamic run within a centimetre, at rest.
    validation(
        "2 t load lowered 195 m (20 -> 215 m, n = 2 -> 21) through a sheared current "
        "(0.5 -> 0.1 m/s) on the reference descent, 200 s",
        "second formulation", "the static equilibrium of the landing line (statics solve)",
        "landing error; vertical speed at the landing",
        f"{report.landing_error:.1e} m; {report.landing_speed:.1e} m/s", "< 1 cm; < 1 mm/s",
    )  # fmt: skip
    assert abs(report.landing_error) < 0.01
    assert abs(report.landing_speed) < 1e-3
    # The checker's top tension is the run's own: the bond force along the top element there,
    # its norm in the run (they differ by the force's small part across the element).
    assert report.peak_tension == pytest.approx(run.top_tension.max(), rel=1e-6)
    assert report.least_tension == pytest.approx(run.top_tension.min(), rel=1e-6)
    assert report.least_bond_tension > 0


def failed(report) -> set[str]:
    return {check.name for check in report.failures}


@pytest.mark.parametrize(
    ("overrides", "broken"),
    [
        ({"lowering.tension_max": None}, set()),
        ({"winch.rate_max": 3.0}, {"drum rate"}),
        ({"winch.acceleration_max": 0.07}, {"drum acceleration"}),
        ({"seabed.minimum_clearance": 5.5}, {"minimum clearance"}),
        ({"lowering.land_time": 160.0}, {"landing height error", "landing speed", "hold band"}),
    ],
)
def test_a_limit_the_run_breaks_is_reported_by_its_check(sheared, overrides, broken):
    scene, descent, run = sheared
    report = check_landing(run, descent.angle, scene.updated(overrides))
    assert failed(report) == broken, str(report)
    for check in report.failures:
        assert "FAILED" in str(check) and check.name in report.reason


def test_tension_limits_just_inside_the_run_are_broken(sheared):
    scene, descent, run = sheared
    first = check_landing(run, descent.angle)
    tight = scene.updated(
        {"lowering.tension_max": 0.999 * first.peak_tension,
         "lowering.tension_min": 1.001 * first.least_tension}
    )  # fmt: skip
    assert failed(check_landing(run, descent.angle, tight)) == {
        "top tension max", "top tension min"
    }  # fmt: skip


def test_a_short_landing_line_fails_the_landing(sheared):
    scene, descent, _ = sheared
    short = replace(descent, landing_line=descent.landing_line - 0.5)
    report = check_landing(co.simulate(scene, winch=short.angle), short.angle)
    assert failed(report) == {"landing height error", "hold band"}
    assert report.landing_error == pytest.approx(0.5, abs=0.01)


def test_a_haul_in_after_the_landing_leaves_the_hold_band(sheared):
    scene, descent, _ = sheared
    creep = -0.01 / scene.winch.drum_radius  # rad/s: 1 cm/s hauled in from 10 s after landing
    begins = scene.lowering.land_time + 10.0

    def creeping(t, left=None):
        phi, rate, acceleration = descent.angle(t)
        s = np.maximum(np.asarray(t, dtype=float) - begins, 0.0)  # a C2 start: s^3 / (s + 1)^2
        phi = phi + creep * s**3 / (s + 1) ** 2
        rate = rate + creep * s**2 * (s + 3) / (s + 1) ** 3
        acceleration = acceleration + creep * 6 * s / (s + 1) ** 4
        return phi, rate, acceleration

    report = check_landing(co.simulate(scene, winch=creeping), creeping)
    assert failed(report) == {"hold band"}
    assert report.hold_deviation > 0.1


def test_a_pushing_bond_is_reported_as_slack(sheared):
    # The same states with an upward pull at the end of twice its load: the bonds must push.
    scene, descent, run = sheared
    segment = run.segments[-1]
    inputs = segment.inputs.copy()
    inputs[:, INPUTS.end_force.start + 2] = 2 * run.top_tension.max()
    pushed = LineTrajectory([*run.segments[:-1], replace(segment, inputs=inputs)], 10.0)
    report = check_landing(pushed, descent.angle)
    assert "no slack bond" in failed(report)
    assert report.least_bond_tension < 0


def test_a_run_that_ends_before_the_landing_is_refused(sheared):
    scene, _, _ = sheared
    short = scene.updated({"numerics.duration": 50.0, "lowering.land_time": 50.0})
    with pytest.raises(ValueError, match=r"ends at 50 s, before lowering\.land_time = 200\.0 s"):
        check_landing(co.simulate(short), scene=scene)


@pytest.mark.slow
def test_deploy_lands_in_open_loop_and_is_held_by_the_closed_loop():
    """The bundled deploy scene (issue 27's acceptance on it): 1000 m of line, H_s = 2 m.

    Open loop: within 0.1 m of the target height and 0.1 m/s, tension within its limits, every
    check on the verified run (2 -> 100 elements). The bare descent, the heave not fed forward,
    rides the heave. Closed loop: the 60 s hold within +/- 0.1 m, its compensation ratio.
    """
    from cable_ocp.lowering.hold import hold
    from cable_ocp.lowering.plan import plan_landing

    scene = co.load_scene(MODELS / "deploy.toml")
    plan = plan_landing(scene)
    assert plan.success, plan.status
    report = plan.report
    assert abs(report.landing_error) < 0.1 and abs(report.landing_speed) < 0.1
    assert scene.lowering.tension_min < report.least_tension < report.peak_tension
    assert report.peak_tension < scene.lowering.tension_max
    assert plan.run.element_count[0] == 2 and plan.run.element_count[-1] >= 100
    bare = check_landing(co.simulate(scene, winch=plan.descent.angle), plan.descent.angle)
    assert {"landing speed", "hold band"} <= failed(bare)
    held = hold(scene)
    assert held.success, held.status
    assert held.deviation < 0.1 and held.compensation_ratio > 90.0
    print(held.status)


def test_the_landing_figure_shows_targets_limits_and_the_verdict(sheared, tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    from cable_ocp.plots.landing import landing

    scene, descent, run = sheared
    report = check_landing(run, descent.angle, scene.updated({"winch.rate_max": 3.0}))
    figure = landing(run, descent, report)
    assert "failed: drum rate" in figure.texts[0].get_text()
    assert "scene paper_flat" in figure.texts[0].get_text()
    for ax in figure.axes:
        assert "[" in ax.get_ylabel()
    path = tmp_path / "landing.png"
    landing(run, descent, path=path)
    assert path.stat().st_size > 10_000


HEAVING = {  # a drum that can pay the heave of H_s = 2 m out: 2.5 m/s^2 of line
    "environment.current_profile": SHEARED,
    "top.heave": {"sea_state": {"significant_height": 2.0, "peak_period": 8.0, "seed": 3}},
    "winch.acceleration_max": 5.0,
}


def test_the_closed_loop_holds_the_landed_load_in_its_band_against_the_heave(tmp_path):
    from cable_ocp.lowering.hold import LINE_TOLERANCE, HoldResult, hold

    scene = lowering_scene(**HEAVING)
    held = hold(scene, duration=40.0)
    assert held.success, held.status
    assert held.deviation <= scene.lowering.hold_band
    assert held.compensation_ratio > 90.0
    # It starts on its target (trimmed for the heave at its start) with the landing's n.
    run = held.mpc.trajectory
    assert abs(run.clearance_error[0]) < LINE_TOLERANCE
    assert held.scene.model.elements == scene.winch.line.mesh.starting_elements(
        held.scene.cable.length
    )
    # The baseline in the same sea: the winch locked, the load rides the heave.
    locked = co.simulate(held.scene)
    assert np.abs(locked.clearance_error).max() > 5 * held.deviation
    assert np.std(locked.end[:, 2]) > 0.8 * np.std(locked.top[:, 2])
    assert "compensation ratio" in held.status
    assert held.peak_acceleration <= scene.winch.acceleration_max
    # Saved and loaded (issue 41): every field, the scene and the closed loop's run restored.
    loaded = co.load_result(held.save(tmp_path / "hold.nc"))
    assert isinstance(loaded, HoldResult) and loaded.status == held.status
    assert loaded.scene.to_dict() == held.scene.to_dict() and loaded.drum == held.drum
    np.testing.assert_array_equal(loaded.mpc.trajectory.end, run.end)
    # The same hold on a drum too slow for the heave: the plant's drum saturates (it keeps
    # within its limit), the load leaves its band, and the result says both.
    slow = hold(scene.updated({"winch.acceleration_max": 1.0}), duration=40.0)
    assert not slow.success and "the drum saturated" in slow.status
    assert slow.peak_acceleration <= 1.0 * (1 + 1e-6) and slow.mpc.saturated_steps > 0


def test_a_hold_refuses_a_moving_vessel_and_a_run_without_hold_time():
    from cable_ocp.lowering.hold import hold_scene

    with pytest.raises(ValueError, match="top.motion = 'tow'"):
        hold_scene(lowering_scene(**{"top.motion": "tow"}))
    with pytest.raises(ValueError, match="leaves no hold"):
        hold_scene(lowering_scene(**{"numerics.duration": 200.0}))


def test_the_open_loop_landing_corrects_its_line_on_the_full_model_and_feeds_the_heave(tmp_path):
    from cable_ocp.lowering.plan import CORRECTION_SHARE, LandingPlan, plan_landing

    scene = lowering_scene(**HEAVING)
    plan = plan_landing(scene)
    assert plan.success, plan.status
    assert plan.heave_feedforward
    errors = np.abs(plan.landing_errors)
    assert errors[-1] <= CORRECTION_SHARE * scene.lowering.height_tolerance
    assert len(errors) == 1 or errors[-1] < errors[0]
    # Fed forward on the approach, the heave is kept off the load at the landing and in the hold;
    # the plan's angle is the one that flew.
    assert plan.report.hold_deviation < scene.lowering.hold_band
    flown = check_landing(plan.run, plan.angle)
    assert flown.landing_error == plan.report.landing_error
    # Saved, loaded and flown again (issue 41): the loaded plan's angle replays its run.
    loaded = co.load_result(plan.save(tmp_path / "plan.nc"))
    assert isinstance(loaded, LandingPlan) and fields_equal(loaded.report, plan.report)
    replayed = co.simulate(loaded.scene, winch=loaded.angle)
    np.testing.assert_allclose(replayed.end, plan.run.end, rtol=0, atol=1e-9)
    # Without the feedforward the same descent leaves the load on the heave.
    bare = check_landing(co.simulate(scene, winch=plan.descent.angle), plan.descent.angle)
    assert "hold band" in failed(bare)


def test_an_open_loop_landing_whose_model_fails_says_so():
    from cable_ocp.lowering.plan import plan_landing

    scene = lowering_scene(**{**HEAVING, "numerics.step": 0.5, "numerics.output_every": 1,
                              "numerics.constraint_tolerance": 1e-9})  # fmt: skip
    plan = plan_landing(scene)
    assert not plan.success and plan.run is None
    assert plan.status.startswith("the full model failed: ")


def toml_value(value) -> str:
    """A Python value as the TOML of a ``--set`` (inline tables and arrays)."""
    if isinstance(value, dict):
        return "{" + ", ".join(f"{k} = {toml_value(v)}" for k, v in value.items()) + "}"
    if isinstance(value, list):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    return repr(value) if not isinstance(value, str) else f'"{value}"'


def test_the_command_line_lands_holds_and_writes_its_figures(tmp_path, capsys):
    import json

    from cable_ocp import cli

    sets = [f"{key}={toml_value(value)}" for key, value in {**LOWERING, **HEAVING}.items()]
    out = tmp_path / "lowered"
    args = ["lower", str(MODELS / "paper_flat.toml"), "--out", str(out), "--quiet"]
    assert cli.main([*args, *(part for s in sets for part in ("--set", s))]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["landing_success"] and summary["hold_success"]
    assert abs(summary["landing_error"]) < 0.01 and summary["compensation_ratio"] > 90
    assert summary["locked_hold_deviation"] > summary["closed_loop_deviation"]
    assert summary["units"]["compensation_ratio"] == "%"
    # From the hover: optimised and closed-loop landings, each checked.
    assert summary["hover_optimised_success"] and summary["hover_closed_loop_success"]
    assert abs(summary["hover_optimised_landing_error"]) < 0.1
    assert summary["hover_closed_loop_compensation_ratio"] > 90
    assert summary["units"]["hover_closed_loop_real_time_factor"] == "1"
    for name in ("landing.nc", "landing.png", "seabed_view.png", "line_run.png",
                 "hold_clearance.png", "hold_drum.png", "hold_tension.png", "hover_optimised.png",
                 "hover_closed_loop.png", "hover_optimised_drum.png",
                 "hover_closed_loop_drum.png"):  # fmt: skip
        assert (out / name).stat().st_size > 0, name
    assert "every check passed" in capsys.readouterr().out
    # A scene without [lowering] is refused before any work, naming what it needs.
    code = cli.main(["lower", str(MODELS / "paper_flat.toml"), "--out", str(tmp_path / "x")])
    assert code == 2 and "lower needs a scene with [lowering]" in capsys.readouterr().err
    assert not (tmp_path / "x").exists()


def test_the_hold_correction_is_c2_zero_before_the_landing_and_learns_the_settling():
    from types import SimpleNamespace

    from cable_ocp.lowering.plan import HOLD_FADE, HoldCorrection

    land, target = 100.0, 5.0
    time = np.arange(0.0, 160.0 + 1e-9, 0.5)
    settling = 0.3 * (1 - np.exp(-np.maximum(time - land, 0.0) / 20.0))  # the end rises 0.3 m
    run = SimpleNamespace(time=time)
    learnt = HoldCorrection.none(land).learnt(run, target, target + 0.01 + settling)
    t = np.linspace(90.0, 159.0, 69_001)
    line, rate, acceleration = learnt.line(t)
    dt = t[1] - t[0]
    assert np.all(line[t < land] == 0.0)
    assert np.abs(np.gradient(line, dt) - rate).max() < 1e-5
    assert np.abs(np.gradient(rate, dt) - acceleration).max() < 1e-3
    # Past the fade it pays out what the run rose after its landing (the landing's own 1 cm is
    # the landing line's to correct, not the hold's).
    late = time > land + HOLD_FADE
    assert np.abs(learnt.line(time[late])[0] - settling[late]).max() < 1e-9
    # Learning again adds the next run's settling to it.
    again = learnt.learnt(run, target, target + settling / 10)
    assert np.abs(again.line(time[late])[0] - 1.1 * settling[late]).max() < 1e-9


def test_the_readmes_lowering_table_loads(tmp_path):
    import re

    readme = (MODELS.parent / "README.md").read_text(encoding="utf-8")
    example = next(b for b in re.findall(r"```toml\n(.*?)```", readme, re.S) if "[lowering]" in b)
    path = tmp_path / "lowering.toml"
    path.write_text("[model]\n[top]\n[numerics]\nduration = 960.0\n" + example, encoding="utf-8")
    lowering = co.load_scene(path).lowering
    assert (lowering.land_time, lowering.height, lowering.tension_max) == (900.0, 5.0, 250000.0)
    deploy = co.load_scene(MODELS / "deploy.toml").lowering
    assert lowering == deploy  # the README shows the bundled scene's table


def test_the_checks_take_a_run_of_fixed_n_too():
    # A scene without [winch.line]: one Trajectory, its own model's bond forces.
    scene = co.load_scene(MODELS / "hanging.toml", {
        "numerics.duration": 10.0, "seabed.clearance": 5.0,
        "lowering": {"land_time": 5.0, "height": 5.0, "tension_min": 1.0},
    })  # fmt: skip
    run = co.simulate(scene)
    report = check_landing(run)
    assert report.passed, str(report)
    assert abs(report.landing_error) < 1e-9 and abs(report.landing_speed) < 1e-9
    assert report.least_tension == pytest.approx(run.top_tension.min(), rel=1e-9)
    assert report.least_bond_tension > 0


def _grid_through(path, landing: np.ndarray, below: float, rise, along: tuple[float, float]):
    """A grid whose seabed lies ``below`` (m) under ``landing``, rising ``rise(dy)`` (m) with
    the distance ``dy`` (m) across the run's drift (y), over the end's path ``along`` (x, m).
    """
    import xarray as xr

    x = np.arange(along[0] - 20.0, along[1] + 20.0, 5.0)
    y = landing[1] + np.linspace(-10.0, 10.0, 401)
    z = landing[2] - below + rise(y - landing[1])
    elevation = np.broadcast_to(z, (x.size, y.size))
    xr.Dataset({"elevation": (("x", "y"), elevation)}, coords={"x": x, "y": y}).to_netcdf(path)
    return str(path)


@pytest.mark.parametrize(
    ("rise", "broken"),
    [
        (lambda dy: np.tan(np.radians(66.0)) * dy, {"seabed slope"}),
        (
            lambda dy: 34.0 * (1 + np.tanh((dy - 1.0) / 0.1)) / 2,
            {"seabed slope", "footprint clearance"},
        ),
        (lambda dy: np.tan(np.radians(15.0)) * dy, {"seabed slope"}),
        (lambda dy: 4.0 * np.exp(-(((dy + 1.2) / 0.4) ** 2)), {"seabed slope"}),  # a boulder
        (lambda dy: np.tan(np.radians(3.0)) * dy, set()),
    ],
    ids=["66 deg slope", "34 m cliff 1 m aside", "15 deg slope", "4 m boulder", "3 deg slope"],
)
def test_the_seabed_is_checked_over_the_loads_footprint(sheared, tmp_path, rise, broken):
    """The sheared landing checked over absolute seabeds that pass under its landing point at
    the same height, sloping or stepping beside it: only the footprint's checks may fail.
    """
    scene, descent, run = sheared
    first = check_landing(run, descent.angle)
    land = int(np.argmin(np.abs(run.time - scene.lowering.land_time)))
    landing = run.end[land]
    grid = _grid_through(tmp_path / "seabed.nc", landing, HEIGHT + first.landing_error, rise,
                         (run.end[:, 0].min(), run.end[:, 0].max()))  # fmt: skip
    report = check_landing(run, descent.angle, scene.updated({"seabed.grid.file": grid}))
    assert report.landing_error == pytest.approx(first.landing_error, abs=1e-3)
    assert failed(report) == broken, str(report)


def test_dnv_slack_criterion_and_dynamic_amplification_on_a_fast_pay_out():
    """A 1 t load on the hanging rope, 10 m paid out in 4.7 s: the top tension dips to 8 % of
    its static value without a bond pushing (DNV's criterion fails); in 5.5 s to 33 % (passes).
    """
    from test_slack import smooth_pay_out

    scene = co.load_scene(MODELS / "hanging.toml", {
        "numerics.duration": 6.0, "numerics.step": 0.01, "winch.top_length_max": 60.0,
        "winch.angle_max": 100.0, "end.payload": {"mass": 1000.0, "volume": 0.1, "drag_area": 1.0},
        "seabed.clearance": 5.0, "lowering": {"land_time": 5.0, "height": 5.0, "tension_min": 1.0},
    })  # fmt: skip
    radius = scene.winch.drum_radius
    fast, slow = (smooth_pay_out(10.0, duration, radius) for duration in (4.7, 5.5))
    run = co.simulate(scene, winch=fast, compiled=True)
    report = check_landing(run, fast)
    assert "slack criterion (DNV-RP-H103)" in failed(report) and "no slack bond" not in failed(
        report
    )
    assert 0.0 < report.least_static_share < 0.1
    # The static top tension, independently: the submerged rope out and the load.
    rope = (scene.cable.density - 1025.0) * scene.cable.cross_section_area * 9.81
    line = scene.cable.length + radius * fast(run.time)[0]
    static = rope * line + (1000.0 - 1025.0 * 0.1) * 9.81
    assert report.dynamic_amplification == pytest.approx(np.max(run.top_tension / static), rel=1e-6)
    assert report.least_static_share == pytest.approx(np.min(run.top_tension / static), rel=1e-6)
    assert "dynamic amplification factor" in str(report)
    calm = check_landing(co.simulate(scene, winch=slow, compiled=True), slow)
    assert "slack criterion (DNV-RP-H103)" not in failed(calm) and calm.least_static_share > 0.3
