"""Simulation of the bundled scenes end to end (cable_ocp.simulation.run).

The top moved by a table, the inputs checked before integrating, heave compensation.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import cable_ocp.simulation.run as simulation
from cable_ocp.drive import vessel
from cable_ocp.model import structured
from cable_ocp.model.cable import CableModel
from cable_ocp.scene.schema import load_scene
from cable_ocp.simulation import outputs
from cable_ocp.simulation.run import simulate

MODELS = Path(__file__).resolve().parent.parent / "models"
SHORT = {"numerics.duration": 100.0}  # paper_flat cut to 100 s: the tow ramp and the end's rise


@pytest.fixture(scope="module")
def flat_short():
    """paper_flat over 100 s (winch locked) and its run."""
    scene = load_scene(MODELS / "paper_flat.toml", SHORT)
    return scene, simulate(scene)


def tow_of(scene) -> vessel.TopMotionFunction:
    top, tow = scene.top, scene.top.tow_profile
    return vessel.tow_profile(
        top.start, tow.surge_speed, tow.sway_speed, tow.ramp_time, tow.sway_period
    )


def test_table_motion_reproduces_the_tow_profile(tmp_path, flat_short, validation):
    """The tow profile sampled every 0.25 s and read back as a table gives the same end path."""
    scene, parametric = flat_short
    duration = scene.numerics.duration
    # The natural spline's velocity at t = 0 is not zero (the tow's is): the table's run starts
    # moving with it, so the two runs differ most at the start.
    times = np.arange(0.0, duration + 1e-9, 0.25)
    path = tmp_path / "tow.csv"
    np.savetxt(path, np.column_stack([times, tow_of(scene)(times)[0].T]), delimiter=",",
               header="t,x,y,z", comments="")  # fmt: skip
    table = scene.updated({"top.motion": "table", "top.table.file": str(path)})
    run = simulate(table)
    np.testing.assert_array_equal(run.time, parametric.time)
    difference = np.linalg.norm(run.end - parametric.end, axis=1).max()
    top = np.abs(run.top - parametric.top).max()
    validation("paper_flat, 100 s, top motion from a table sampled every 0.25 s",
               "second formulation", "the same run with the analytic tow profile",
               "max end difference; max top difference", f"{difference:.1e} m; {top:.1e} m",
               "< 0.01 m; < 1e-3 m")  # fmt: skip
    assert difference < 0.01  # m
    assert top < 1e-3  # m: the top follows the table


# --- inputs checked before integrating ---------------------------------------------------------


@pytest.fixture(scope="module")
def flat_scene():
    return load_scene(MODELS / "paper_flat.toml")


def test_wrong_number_of_knots(flat_scene):
    with pytest.raises(ValueError, match=r"winch\.knots = 14"):
        simulate(flat_scene, winch=np.zeros(13))


def test_top_length_bounds_checked_before_integrating(flat_scene, monkeypatch):
    def never(*args, **kwargs):
        raise AssertionError("reached the integrator")

    monkeypatch.setattr(simulation, "integrate", never)
    monkeypatch.setattr(simulation, "starting_state", never)
    # Pay-out: 10 m + 0.5 m x 30 rad = 25 m > top_length_max = 22 m.
    capped = flat_scene.updated({"winch.top_length_max": 22.0})
    with pytest.raises(ValueError, match=r"m at t = .* beyond winch\.top_length_max = 22 m"):
        simulate(capped, winch=np.full(14, 30.0))
    # Haul-in: 10 m - 0.5 m x 17 rad = 1.5 m < top_length_min = 2 m.
    with pytest.raises(ValueError, match=r"m at t = .* beyond winch\.top_length_min = 2 m"):
        simulate(flat_scene, winch=np.linspace(-1.0, -17.0, 14))


def test_library_entry_points_reject_bad_numbers_before_integrating(monkeypatch):
    def forbidden(*args, **kwargs):
        pytest.fail("bad input must be refused before any heavy work")

    monkeypatch.setattr(simulation, "starting_state", forbidden)
    monkeypatch.setattr(simulation, "integrate", forbidden)
    scene = load_scene(
        MODELS / "hanging.toml", {"model.elements": 2, "winch.top_length_max": 160.0}
    )
    knots = np.zeros(scene.winch.knots)
    with pytest.raises(ValueError, match=r"^winch: knot value 3 is nan: must be finite \(rad\)$"):
        simulation.simulate(scene, winch=np.where(np.arange(knots.size) == 2, np.nan, knots))
    with pytest.raises(ValueError, match=r"^winch: 2 knot values given; .* winch\.knots = 14$"):
        simulation.simulate(scene, winch=[0.0, 1.0])
    with pytest.raises(ValueError, match=r"^winch: expected 14 knot angles in rad$"):
        simulation.simulate(scene, winch=["a"] * 14)
    size = 2 * 5 * 3  # 5 coordinates per element, n + 1 = 3 elements, positions and rates
    with pytest.raises(
        ValueError,
        match=rf"^initial_state has shape \(29,\) for the model's state of shape \({size},\)$",
    ):
        simulation.simulate(scene, initial_state=np.zeros(size - 1))
    with pytest.raises(ValueError, match=r"^initial_state is str, not numbers$"):
        simulation.simulate(scene, initial_state="state")
    with pytest.raises(ValueError, match=r"^initial_state\[4\] is nan, not finite$"):
        simulation.simulate(scene, initial_state=np.where(np.arange(size) == 4, np.nan, 0.0))


# --- heave and its compensation ----------------------------------------------------------------


def test_heave_compensation_keeps_the_end_still(validation):
    heave = {
        "numerics.duration": 20.0,
        "top.heave.amplitude": 1.0,
        "top.heave.period": 10.0,
        "top.heave.compensation": True,
    }
    compensated = simulate(load_scene(MODELS / "hanging.toml", heave))
    # The heave starts at full speed (a omega = 0.63 m/s): the locked run starts moving with the
    # top, so its bonds hold from the first step at the scene's tolerance.
    free = simulate(load_scene(MODELS / "hanging.toml", {**heave, "top.heave.compensation": False}))
    still = np.linalg.norm(compensated.end - compensated.end[0], axis=1).max()
    moving = np.linalg.norm(free.end - free.end[0], axis=1).max()
    validation("hanging, n = 10, 1 m heave of 10 s period, 20 s", "analytic",
               "compensated: the cable below the top element never moves; locked: the end "
               "follows the top", "max end displacement, compensated; locked",
               f"{still:.1e} m; {moving:.4f} m", "< 1e-6 m; 1 m +- 1 mm")  # fmt: skip
    # The top heaves 2 m peak to peak in both runs (tolerance 1e-9 m).
    np.testing.assert_allclose(np.ptp(compensated.inputs[:, 2]), 2.0, atol=1e-9)
    # Compensated the winch pays out what the top rises: top element 15 m +- 1 m.
    np.testing.assert_allclose(compensated.top_length - compensated.inputs[:, 2], 15.0, atol=1e-9)
    assert still < 1e-6  # m
    # Without compensation the hanging chain, rigid along its axis, follows the top's 1 m.
    assert moving == pytest.approx(1.0, abs=1e-3)
    assert np.ptp(free.top_length) == 0.0


def test_a_heaving_tow_starts_moving_with_its_top():
    """paper_hill with a 1 m, 8 s heave: the heave starts at 0.79 m/s, and the run keeps its bonds
    within the scene's 1e-4 m from the first step (it used to stop at t = 0.05 s)."""
    heave = {"top.heave.amplitude": 1.0, "top.heave.period": 8.0, "numerics.duration": 20.0}
    run = simulate(load_scene(MODELS / "paper_hill.toml", heave), compiled=True)
    assert run.time[-1] == pytest.approx(20.0)
    # The end rises with the top in the first quarter period.
    quarter = np.searchsorted(run.time, 2.0)
    assert run.end[quarter, 2] - run.end[0, 2] > 0.5


@pytest.mark.parametrize("compiled", [False, True])
def test_joints_and_tensions_in_blocks_are_those_of_one_call(monkeypatch, compiled):
    """The outputs evaluated block by block (map's cost grows faster than its count) are exact."""
    scene = load_scene(Path(__file__).resolve().parent.parent / "models" / "hanging.toml",
                       {"model.elements": 6, "numerics.duration": 2.0})  # fmt: skip
    run = simulate(scene, compiled=compiled)
    model = CableModel.from_scene(scene)
    whole = outputs.run_outputs(model, run.states, run.inputs, compiled)
    monkeypatch.setattr(outputs, "OUTPUT_BLOCK", 7)
    blocks = outputs.run_outputs(model, run.states, run.inputs, compiled)
    assert len(run.states) % 7  # a shorter last block
    for single, blocked in zip(whole, blocks, strict=True):
        np.testing.assert_array_equal(blocked, single)
    # The norms are the model's own tensions output to the last bit, compiled or not.
    mapped = model.outputs.map(len(run.states))(run.states.T, run.inputs.T)
    np.testing.assert_allclose(whole[1], np.array(mapped[5]).T, rtol=1e-13)
    if compiled:
        structured_norms = structured.compiled_structured(model, "outputs", 1)
        first = structured_norms(run.states[0], run.inputs[0])[1]
        np.testing.assert_array_equal(whole[1][0], np.array(first).ravel())
