"""A run whose physics is impossible never exits 0 (issue 45 item 2): the command line's side."""

import json

import numpy as np

from cable_ocp.cli import main

# The hanging rope with a 1 t load, 10 m paid out in 3 s (5 m/s at the peak): faster than the
# load sinks, so the rope would have to push it down (tests/test_slack.py, by the API).
FAST_PAY_OUT = [
    "--set", "numerics.duration=6", "--set", "numerics.step=0.01",
    "--set", "numerics.constraint_tolerance=1e-4", "--set", "winch.top_length_max=60",
    "--set", "winch.angle_max=100",
    "--set", "end.payload={mass=1000.0, volume=0.1, drag_area=1.0}",
]  # fmt: skip


def _knots(distance: float, duration: float) -> str:
    t = np.arange(1, 15) * 6.0 / 14
    tau = np.clip(t / duration, 0.0, 1.0)
    angle = distance / 0.5 * tau**3 * (10 - 15 * tau + 6 * tau**2)  # hanging's drum r_D = 0.5 m
    return ",".join(f"{value:.4f}" for value in angle)


def test_a_pushing_rope_exits_3_with_its_results_written(tmp_path, capsys):
    out = tmp_path / "run"
    code = main(["simulate", "hanging", *FAST_PAY_OUT, "--knots", _knots(10.0, 3.0),
                 "--out", str(out), "--quiet"])  # fmt: skip
    assert code == 3
    error = capsys.readouterr().err
    assert "cable-ocp simulate: error: the run is not physical: rope pushes" in error
    summary = json.loads((out / "summary.json").read_text())
    assert summary["success"] is False and summary["top_tension_min"] < -1e4
    assert summary["units"]["top_tension_min"] == "N"
    assert (out / "trajectory.nc").exists()


def test_the_same_pay_out_slow_enough_exits_0(tmp_path):
    out = tmp_path / "run"
    code = main(["simulate", "hanging", *FAST_PAY_OUT, "--set", "numerics.duration=12",
                 "--knots", _knots(2.0, 10.0), "--out", str(out), "--quiet"])  # fmt: skip
    assert code == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["success"] is True and summary["top_tension_min"] > 0
