"""The drum's range after a run (cable_ocp.simulation.drum_range, issue 45, D3).

A run whose drum turns beyond ``[winch.angle_min, winch.angle_max]`` fails its physics check and
says which field, the angle reached and when; the command line writes its results and exits 3.
Within :data:`~cable_ocp.drive.bounds.BOUND_TOLERANCE` of the bound it passes.
"""

from __future__ import annotations

import json
from types import SimpleNamespace

import numpy as np
import pytest

import cable_ocp as co
from cable_ocp.cli import main
from cable_ocp.drive.bounds import BOUND_TOLERANCE
from cable_ocp.simulation.drum_range import drum_failure

MODELS = "models"


@pytest.fixture(scope="module")
def short_hanging():
    """The hanging rope for 4 s, its drum allowed 0.5 rad of pay-out and 0.3 of haul-in."""
    return co.load_scene(f"{MODELS}/hanging.toml").updated(
        {"numerics.duration": 4.0, "winch.angle_max": 0.5, "winch.angle_min": -0.3,
         "winch.knots": 4}
    )  # fmt: skip


def test_a_drum_beyond_angle_max_fails_naming_the_field_angle_and_time(short_hanging):
    """Knots up to 0.8 rad on a 0.5 rad drum: the run fails, naming winch.angle_max."""
    run = co.simulate(short_hanging, winch=[0.2, 0.4, 0.6, 0.8], compiled=True)
    assert run.physics.slack.least_bond_tension > 0  # the rope pulls: only the drum fails
    assert not run.success
    assert run.status.startswith("the drum turned to 0.8 rad at t = 4 s, beyond ")
    assert "winch.angle_max = 0.5 rad" in run.status
    first = float(run.status.split("outside from t = ")[1].split(" s")[0])
    assert first == pytest.approx(run.time[np.argmax(run.winch_angle > 0.5 + BOUND_TOLERANCE)])
    assert run.summary()["success"] is False


def test_a_drum_hauled_in_beyond_angle_min_fails(short_hanging):
    run = co.simulate(short_hanging, winch=[-0.1, -0.2, -0.3, -0.4], compiled=True)
    assert not run.success
    assert "beyond winch.angle_min = -0.3 rad" in run.status


def test_a_drum_within_its_range_passes_and_says_so(short_hanging):
    run = co.simulate(short_hanging, winch=[0.1, 0.2, 0.3, 0.5], compiled=True)
    assert run.success, run.status
    assert run.status.endswith("the drum within its range")


def test_the_bound_tolerance_counts_as_within():
    """``BOUND_TOLERANCE`` beyond the bound passes, ten times that fails (as for the solvers)."""
    winch = SimpleNamespace(angle_min=-1.0, angle_max=2.0)
    time = np.array([0.0, 1.0, 2.0])
    assert drum_failure(winch, time, np.array([0.0, 2.0 + 0.5 * BOUND_TOLERANCE, 1.0])) is None
    assert drum_failure(winch, time, np.array([-1.0 - 0.5 * BOUND_TOLERANCE, 0.0, 0.0])) is None
    text = drum_failure(winch, time, np.array([0.0, 2.0 + 10 * BOUND_TOLERANCE, 1.0]))
    assert text is not None and "at t = 1 s, beyond winch.angle_max = 2 rad" in text


def test_the_command_line_writes_the_run_and_exits_3(tmp_path, capsys):
    out = tmp_path / "run"
    code = main(["simulate", "hanging", "--set", "numerics.duration=4",
                 "--set", "winch.angle_max=0.5", "--set", "winch.knots=4",
                 "--knots", "0.2,0.4,0.6,0.8", "--out", str(out), "--quiet"])  # fmt: skip
    assert code == 3
    assert "not physical: the drum turned to 0.8 rad" in capsys.readouterr().err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["success"] is False and "winch.angle_max" in summary["status"]
    assert (out / "trajectory.nc").exists()


def test_a_drum_faster_than_rate_max_fails_naming_the_field_rate_and_time(short_hanging):
    """0.2 rad/s of pay-out on a winch of 0.1 rad/s: the run fails on winch.rate_max."""
    scene = short_hanging.updated({"winch.angle_max": 10.0, "winch.rate_max": 0.1})
    run = co.simulate(scene, winch=[0.2, 0.4, 0.6, 0.8], compiled=True)
    assert not run.success
    assert run.status.startswith("the drum turned at ")
    assert "beyond winch.rate_max = 0.1 rad/s" in run.status
    rate = float(run.status.split("turned at ")[1].split(" rad/s")[0])
    steepest = np.max(np.abs(np.gradient(run.winch_angle, run.time)))
    assert rate > 0.1 and rate == pytest.approx(steepest, rel=0.05)
    assert "acceleration_max" not in run.status


def test_a_drum_harder_than_acceleration_max_is_a_note_naming_field_and_time(short_hanging):
    """An acceleration beyond its bound is a note (an optimum's heave feedforward replayed on its
    scene legitimately exceeds it), the run passes."""
    scene = short_hanging.updated({"winch.angle_max": 10.0, "winch.acceleration_max": 1e-3})
    run = co.simulate(scene, winch=[0.2, 0.4, 0.6, 0.8], compiled=True)
    assert run.success, run.status
    note = run.physics.acceleration_note
    assert note is not None and "beyond winch.acceleration_max = 0.001 rad/s^2" in note
    assert "rad/s^2 at t = " in note and "(a note" in note and "cannot" not in note
    assert note in run.physics.notes


def test_a_profile_within_rate_and_acceleration_limits_passes(short_hanging):
    scene = short_hanging.updated(
        {"winch.angle_max": 10.0, "winch.rate_max": 1.0, "winch.acceleration_max": 10.0}
    )
    run = co.simulate(scene, winch=[0.2, 0.4, 0.6, 0.8], compiled=True)
    assert run.success, run.status
    assert run.status.endswith("the drum within its range")
    assert run.physics.acceleration_note is None


def test_heave_compensation_counts_on_top_of_the_rate_limit():
    """A locked profile compensating a 1 m, 6 s heave: the drum turns ~1 rad/s, yet the
    commanded profile is at rest, so a rate limit of 0.01 rad/s holds (as for the optimiser)."""
    scene = co.load_scene(f"{MODELS}/hanging.toml").updated(
        {"numerics.duration": 3.0, "top.heave.amplitude": 1.0, "top.heave.period": 6.0,
         "top.heave.compensation": True, "winch.rate_max": 0.01, "winch.acceleration_max": 0.01}
    )  # fmt: skip
    run = co.simulate(scene, compiled=True)
    assert np.max(np.abs(np.gradient(run.winch_angle, run.time))) > 0.1  # the drum does turn
    assert run.physics.rate_failure is None and run.physics.acceleration_note is None
