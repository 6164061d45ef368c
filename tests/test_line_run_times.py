"""A pay-out run's errors name the run's time, not the time within its segment (issue 45).

A line run integrates segments of constant ``n``, each from its own ``t = 0``
(:mod:`cable_ocp.simulation.line_run`); a failure in a later segment must say when in the run
it happened, and in which segment.
"""

from __future__ import annotations

import re

import pytest

import cable_ocp as co
from cable_ocp.drive.drive import Drive
from cable_ocp.model.cable import CableModel
from cable_ocp.simulation.integrate import SimulationError, integrate
from cable_ocp.simulation.statics import starting_state
from cable_ocp.simulation.winch_input import winch_function

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


def test_a_run_names_its_failure_on_the_callers_clock():
    """integrate's ``time_origin`` (a segment's start) is added to the time of its failure."""
    scene = co.load_scene("paper_flat", {"model.elements": 3, "numerics.duration": 2.0})
    model = CableModel.from_scene(scene)
    drive = Drive.from_scene(scene, winch_function(scene, None), elements=3)
    start = starting_state(model, drive)
    step = scene.numerics.step
    times = []
    for origin in (0.0, 62.25):
        with pytest.raises(SimulationError) as caught:  # no run keeps its bonds to 1e-18 m
            integrate(model, start, drive, 2.0, step, tolerance=1e-18, time_origin=origin)
        times.append(float(re.search(r"at t = ([\d.]+) s with step", str(caught.value))[1]))
    assert times[0] == pytest.approx(step)  # the first step's residual is already beyond it
    assert times[1] == pytest.approx(62.25 + step)
