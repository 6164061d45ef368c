"""A pay-out run's errors name the run's time, not the time within its segment (issue 45).

A line run integrates segments of constant ``n``, each from its own ``t = 0``
(:mod:`cable_ocp.simulation.line_run`); a failure in a later segment must say when in the run
it happened, and in which segment.
"""

from __future__ import annotations

import re

import pytest

import cable_ocp as co
from cable_ocp.simulation.integrate import SimulationError
from cable_ocp.simulation.line_run import in_run_time

SCENE = """
name = "short_pay_out"
[cable]
length = 30.0
diameter = 0.04
[model]
elements = 3
[top]
motion = "fixed"
[end.payload]
mass = 1000.0
volume = 0.128
drag_area = 1.0
[winch]
drum_radius = 1.0
knots = 4
angle_min = -10.0
[winch.line]
pay_out_max = 600.0
haul_in_max = 10.0
element_length = 5.0
[numerics]
duration = 20.0
step = 0.05
constraint_tolerance = 3.0e-7
"""


def test_a_failure_in_a_later_segment_names_the_run_time(tmp_path):
    """Held 5 s, then 60 m paid out: the bonds leave 3e-7 m in a segment after t = 10 s."""
    path = tmp_path / "short_pay_out.toml"
    path.write_text(SCENE)
    with pytest.raises(SimulationError) as caught:
        co.simulate(co.load_scene(path), winch=[0.0, 0.0, 20.0, 60.0], compiled=True)
    text = str(caught.value)
    segment = re.match(r"in the segment of (\d+) elements from t = ([\d.]+) s: bond residual", text)
    assert segment is not None, text
    start = float(segment[2])
    assert start > 10.0  # a later segment, not the first
    when = float(re.search(r"at t = ([\d.]+) s with step", text)[1])
    assert start <= when <= 20.0  # the run's time: within the segment, not from its start


def test_every_time_of_a_message_is_shifted_by_the_segment_start():
    text = in_run_time("the state became non-finite at t = 0.05 s; at t <= 1.5e+02 s", 62.25, 9)
    assert text == (
        "in the segment of 9 elements from t = 62.25 s: "
        "the state became non-finite at t = 62.3 s; at t <= 212.25 s"
    )
