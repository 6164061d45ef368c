"""The closed loop's plant runs on simulation.integrate's runner and health check (issue 41)."""

from __future__ import annotations

import numpy as np
import pytest

from cable_ocp.control.closed_loop.plant import Plant
from cable_ocp.drive.drive import Drive
from cable_ocp.scene.schema import load_scene
from cable_ocp.simulation.integrate import integrate


def locked(t, left=None):
    return tuple(np.zeros((3, np.size(t))))


@pytest.fixture(scope="module")
def calm(models_dir):
    """The hanging rope for 2 s (a scene other than the closed loop's paper_hill)."""
    return load_scene(models_dir / "hanging.toml", {"numerics.duration": 2.0})


def test_the_plant_steps_as_a_simulation_does(calm):
    """Locked, from the same state: the plant's states are integrate's, to the last bit."""
    plant = Plant(calm, (calm.winch.angle_min, calm.winch.angle_max), 0.5)
    start = plant.start(locked)
    sample = plant.make_step(locked, 2.0)
    run = integrate(plant.model, start.states[0], Drive.from_scene(calm), 2.0, calm.numerics.step,
                    tolerance=calm.numerics.constraint_tolerance, compiled=True)  # fmt: skip
    np.testing.assert_array_equal(sample.inputs, run.inputs[1:])
    np.testing.assert_array_equal(sample.states, run.states[1:])


def test_the_plant_names_a_broken_state_as_a_simulation_does(calm):
    plant = Plant(calm, (calm.winch.angle_min, calm.winch.angle_max), 0.5)
    start = plant.start(locked)
    x, u = start.states[0].copy(), start.inputs[0]
    assert plant._health(x, u, 1.0, 4) is None
    x[3] = np.nan
    assert plant._health(x, u, 1.0, 4).startswith(
        "the state became non-finite at t = 1 s with step h = 0.0125 s"
    )
    x = start.states[0].copy()
    x[0] += 1.0  # the end moved off its bond by 1 m
    assert "bond residual" in plant._health(x, u, 1.0, 1)
