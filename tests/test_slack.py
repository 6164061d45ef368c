"""Slack, compression and the seabed after a run (cable_ocp.simulation.slack, issues 44 and 45).

A rope pulls and never pushes: a run whose bonds push beyond the stated tolerance, or whose end
goes under an absolute seabed, fails its physics check and says where and when; the signed top
tension is what a run's summary reports.
"""

from __future__ import annotations

from dataclasses import replace

import matplotlib.pyplot as plt
import numpy as np
import pytest
import xarray as xr

import cable_ocp as co
from cable_ocp.model.cable import spec_from_scene
from cable_ocp.plots import significant
from cable_ocp.plots.drum_limits import drum_use
from cable_ocp.plots.tension import tension_against_static
from cable_ocp.scene.schema import scene_of
from cable_ocp.simulation import slack
from cable_ocp.simulation.line_trajectory import LineTrajectory
from cable_ocp.simulation.trajectory import Trajectory

MODELS = "models"


def smooth_pay_out(distance: float, duration: float, radius: float):
    """A winch paying ``distance`` (m) out over ``duration`` (s) by the quintic smoothstep."""

    def angle(t, left=None):
        tau = np.clip(np.asarray(t, dtype=float) / duration, 0.0, 1.0)
        scale = distance / radius
        return (
            scale * tau**3 * (10 - 15 * tau + 6 * tau**2),
            scale * 30 * tau**2 * (1 - tau) ** 2 / duration,
            scale * (60 * tau - 180 * tau**2 + 120 * tau**3) / duration**2,
        )

    return angle


@pytest.fixture(scope="module")
def loaded_hanging():
    """The hanging rope with a 1 t load, 6 s at h = 0.01 s, a top element that may grow."""
    return co.load_scene(f"{MODELS}/hanging.toml").updated(
        {"numerics.duration": 6.0, "numerics.step": 0.01, "winch.top_length_max": 60.0,
         "winch.angle_max": 100.0, "end.payload.mass": 1000.0, "end.payload.volume": 0.1,
         "end.payload.drag_area": 1.0}
    )  # fmt: skip


def test_a_drum_paying_out_faster_than_the_load_sinks_fails_and_says_where(loaded_hanging):
    """10 m paid out in 3 s (5 m/s at its peak) pushes a 1 t load down: the rope pushes."""
    radius = loaded_hanging.winch.drum_radius
    run = co.simulate(loaded_hanging, winch=smooth_pay_out(10.0, 3.0, radius), compiled=True)
    assert not run.success
    assert run.status.startswith("rope pushes beyond")
    summary = run.summary()
    assert summary["success"] is False and summary["top_tension_min"] < -1e4
    assert summary["top_tension_min"] == pytest.approx(run.top_tension.min())
    assert summary["units"]["top_tension_min"] == "N"
    worst = next(e for e in run.physics.slack.events if e.what.startswith("rope pushes"))
    assert 0.0 < worst.first < worst.time < 3.0 and worst.duration > 0.5
    assert worst.bond == run.tensions.shape[1]  # the top bond pushes hardest
    assert any("in compression" in note for note in summary["notes"])
    # Its figure: the top tension below zero, past the push at which the run fails.
    figure = tension_against_static(run, ["5 m/s pay-out"])
    texts = [text.get_text() for text in figure.axes[0].get_legend().get_texts()]
    push = significant(1e-3 * run.physics.slack.compression_tolerance)
    assert f"a push of {push} kN fails the run" in texts
    least = significant(1e-3 * run.top_tension.min())
    assert texts[0].startswith(f"5 m/s pay-out: least {least} kN (-")  # a push: below 0 %
    assert "slack line: 10% of static (DNV-RP-H103)" in texts
    assert figure.axes[0].get_ylabel() == "top tension [kN]"
    plt.close(figure)


def test_the_same_pay_out_slow_enough_passes(loaded_hanging):
    """10 m over 6 s (2.5 m/s at its peak): the load sinks as fast, every bond pulls."""
    radius = loaded_hanging.winch.drum_radius
    run = co.simulate(loaded_hanging, winch=smooth_pay_out(10.0, 6.0, radius), compiled=True)
    assert run.success, run.status
    assert run.status.startswith("physics checked")
    assert run.physics.slack.least_bond_tension > 0
    assert run.summary()["top_tension_min"] > 0


def test_signed_tensions_of_a_hanging_rope_are_its_norms():
    """At rest every bond pulls along its element: the projection is the norm (1e-9)."""
    scene = co.load_scene(f"{MODELS}/hanging.toml").updated({"numerics.duration": 1.0})
    run = co.simulate(scene, compiled=True)
    np.testing.assert_allclose(run.signed_tensions, run.tensions, rtol=1e-9)
    # The static tension is the weight below each bond, which a rope at rest carries.
    static = slack.run_static(run, co.CableModel.from_scene(scene).spec)
    np.testing.assert_allclose(run.signed_tensions, static, rtol=1e-6)


def test_a_force_reversed_along_the_axis_is_a_push():
    joints = np.array([[0.0, 0.0], [0.0, 0.0], [-10.0, 0.0]])  # one element, hanging
    pull = np.array([[0.0], [0.0], [-5.0]])  # the bond pulls the element up
    assert slack.signed_tensions(joints, pull)[0] == pytest.approx(5.0)
    assert slack.signed_tensions(joints, -pull)[0] == pytest.approx(-5.0)


def test_slack_report_names_first_time_duration_and_worst():
    """Synthetic tensions of 3 bonds over 5 samples, static 100 N each."""
    time = np.arange(5.0)
    static = np.full((5, 3), 100.0)
    signed = np.array(
        [[50, 80, 100], [50, 80, 5], [50, -0.5, 50], [50, -30, 50], [50, 80, 100]], dtype=float
    )
    report = slack.slack_report(time, signed, static)
    assert report.compression_tolerance == pytest.approx(slack.COMPRESSION_SHARE * 100)
    events = {e.what: e for e in report.events}
    top = events["top tension below 10% of static"]
    assert (top.first, top.duration, top.worst, top.time, top.bond) == (1.0, 1.0, 5.0, 1.0, 3)
    assert "top tension in compression" not in events
    pushing = events["rope pushes beyond 1 N"]
    assert (pushing.first, pushing.worst, pushing.bond) == (3.0, -30.0, 2)
    compressed = events["bond in compression"]
    assert (compressed.first, compressed.duration) == (2.0, 2.0)
    assert report.pushing and report.least_static_share == pytest.approx(-0.3)


def test_a_line_paid_out_faster_than_the_frame_sinks_fails(tmp_path):
    """Deploy's 5 t frame (terminal speed about 3.3 m/s) under 200 m paid out in 30 s."""
    record = co.load_scene(f"{MODELS}/deploy.toml").to_dict()
    record.pop("lowering")
    record["top"].pop("heave")
    record["numerics"] |= {"duration": 40.0, "output_every": 4}
    record["model"]["axial"] = "rigid"
    scene = scene_of(record, "fast pay-out")
    run = co.simulate(scene, winch=smooth_pay_out(200.0, 30.0, scene.winch.drum_radius))
    assert not run.success and "rope pushes" in run.status
    summary = run.summary()
    assert summary["top_tension_min"] < -1e4 < summary["top_tension_max"]
    assert summary["line_out_range"] == pytest.approx([20.0, 220.0])
    # Saved and read again, the run keeps its signs and fails the same way.
    back = LineTrajectory.load(run.save(tmp_path / "line"))
    assert back.summary() == summary
    # A line paid out by elements is drawn too: its static grows with the line out.
    figure = tension_against_static(back, path=tmp_path / "tension.png")
    assert (tmp_path / "tension.png").stat().st_size > 1000
    static = 1e3 * figure.axes[0].get_lines()[1].get_ydata()  # N
    wire = spec_from_scene(back.scene).element.submerged_weight_per_length  # N/m
    assert static[-1] - static[0] == pytest.approx(200.0 * wire, rel=1e-3)  # 220 m out, not 20
    with pytest.raises(TypeError, match="not LineTrajectory .a line paid out by elements"):
        drum_use(back)  # its line out is plots.line_run's


def _flat_grid(path, depth: float):
    x = np.linspace(-200.0, 200.0, 9)
    elevation = np.full((x.size, x.size), -depth)
    xr.Dataset({"elevation": (("x", "y"), elevation)}, coords={"x": x, "y": x}).to_netcdf(path)
    return path


def test_an_end_paid_out_under_an_absolute_seabed_fails_with_time_and_depth(tmp_path):
    """The 300 m rope over a flat seabed 310 m deep: 20 m paid out take its end 10 m under."""
    scene = co.load_scene(f"{MODELS}/hanging.toml").updated(
        {"numerics.duration": 20.0, "winch.top_length_max": 60.0, "winch.angle_max": 100.0,
         "seabed.grid.file": str(_flat_grid(tmp_path / "flat.nc", 310.0)),
         "seabed.clearance": 5.0, "seabed.minimum_clearance": 2.0}
    )  # fmt: skip
    radius = scene.winch.drum_radius
    run = co.simulate(scene, winch=smooth_pay_out(20.0, 15.0, radius), compiled=True)
    assert not run.success
    assert "under the seabed" in run.status and "no seabed contact" in run.status
    depth = float(run.status.split("the end goes ")[1].split(" m")[0])
    assert depth == pytest.approx(-310.0 - run.end[:, 2].min(), abs=1e-3)
    # Paid out 9 m only, the end stays 1 m above the seabed, under the minimum clearance: a note.
    near = co.simulate(scene, winch=smooth_pay_out(9.0, 15.0, radius), compiled=True)
    assert near.success, near.status
    assert any("seabed.minimum_clearance = 2" in note for note in near.summary()["notes"])


def test_a_run_without_signed_tensions_says_compression_is_unknown(loaded_hanging):
    run = co.simulate(loaded_hanging.updated({"numerics.duration": 0.5}), compiled=True)
    old = replace(run, signed_tensions=np.zeros((0, 0)))
    assert old.success and not old.physics.slack.signed
    assert "compression unknown" in old.summary()["notes"][0]
    np.testing.assert_array_equal(old.top_tension, run.tensions[:, -1])


def test_signed_tensions_are_saved_and_read(tmp_path, loaded_hanging):
    run = co.simulate(loaded_hanging.updated({"numerics.duration": 0.5}), compiled=True)
    back = Trajectory.load(run.save(tmp_path / "run"))
    assert back.equals(run) and back.kept_signs


def test_a_line_paid_out_under_the_seabed_grid_fails_with_time_and_depth(tmp_path):
    """Deploy's frame on 20 m of line over a flat seabed 50 m deep, 60 m paid out in 40 s
    (1.7 m/s at most, slower than the frame sinks): the end goes about 30 m under the grid."""
    record = co.load_scene(f"{MODELS}/deploy.toml").to_dict()
    record.pop("lowering")
    record["top"].pop("heave")
    record["numerics"] |= {"duration": 50.0, "output_every": 4}
    record["model"]["axial"] = "rigid"
    record["seabed"] |= {"grid": {"file": str(_flat_grid(tmp_path / "shelf.nc", 50.0))}}
    scene = scene_of(record, "pay-out into the seabed")
    run = co.simulate(scene, winch=smooth_pay_out(60.0, 40.0, scene.winch.drum_radius))
    assert run.physics.slack.least_bond_tension > 0  # the rope pulls: only the seabed fails
    assert not run.success and run.status.startswith("the end goes ")
    depth = float(run.status.split("the end goes ")[1].split(" m")[0])
    assert depth == pytest.approx(-50.0 - run.end[:, 2].min(), abs=1e-3) and depth > 25.0
    first = float(run.status.split("under it from t = ")[1].split(" s")[0])
    assert first == pytest.approx(run.time[np.argmax(run.end[:, 2] < -50.0 - 1e-3)])


def test_an_end_under_a_relative_seabed_is_a_note_and_the_status_says_so(short_hanging_relative):
    """The hanging rope 0.5 m over a relative seabed, 1 m paid out: the end goes under it. The
    run passes (a relative seabed is the scene's drawing), and status and note agree."""
    scene = short_hanging_relative
    run = co.simulate(scene, winch=smooth_pay_out(1.0, 3.0, scene.winch.drum_radius), compiled=True)
    assert run.success, run.status
    assert any(note.startswith("the end goes ") for note in run.physics.notes)
    assert "the end under the relative seabed (a note)" in run.status
    assert "above the seabed" not in run.status
    # Paid out 0.2 m only, it stays above, and the status says that.
    above = co.simulate(scene, winch=smooth_pay_out(0.2, 3.0, scene.winch.drum_radius),
                        compiled=True)  # fmt: skip
    assert "the end above the seabed" in above.status and not above.physics.end_under_seabed


@pytest.fixture(scope="module")
def short_hanging_relative():
    """The hanging rope for 4 s, a relative seabed 0.5 m under its end."""
    return co.load_scene(f"{MODELS}/hanging.toml").updated(
        {"numerics.duration": 4.0, "seabed.clearance": 0.5}
    )
