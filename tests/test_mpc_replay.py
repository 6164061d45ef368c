"""A closed loop's applied winch replays through ``simulate`` (issue 45 item 8), and the front
doors take a scene file's path or a bundled name."""

import numpy as np
import pytest
from conftest import MODELS

import cable_ocp as co

HEAVE = {"top.heave": {"amplitude": 0.5, "period": 8.0}}


@pytest.fixture(scope="module")
def looped():
    scene = co.load_scene(MODELS / "small_tow.toml", HEAVE)
    return scene, co.mpc(scene, quiet=True)


def test_a_closed_loops_winch_replays_its_run(looped):
    scene, result = looped
    assert result.success, result.status
    replay = co.simulate(scene, winch=result)
    # The drum's angle between the plant's steps is a spline through them: 1 mm is the bound.
    assert np.abs(replay.end - result.trajectory.end).max() < 1e-3
    assert replay.omega == pytest.approx(result.omega, rel=0.05)


def test_another_duration_is_refused_unless_retimed(looped):
    scene, result = looped
    shorter = scene.updated({"numerics.duration": 20.0})
    with pytest.raises(ValueError, match=r"made for 40 s.*retimed\('hold'\)"):
        co.simulate(shorter, winch=result)
    longer = scene.updated({"numerics.duration": 60.0})
    held = co.simulate(longer, winch=result.retimed("hold"))
    assert held.time[-1] == 60.0
    with pytest.raises(ValueError, match="retime = 'slow'"):
        result.retimed("slow")


def test_a_compensating_scene_is_refused_for_the_replay(looped):
    scene, result = looped
    compensated = scene.updated({"top.heave.compensation": True})
    with pytest.raises(ValueError, match="heave feedback"):
        co.simulate(compensated, winch=result)


def test_simulate_and_mpc_take_a_path_or_a_bundled_name():
    by_path = co.simulate(str(MODELS / "small_tow.toml"))
    by_name = co.simulate("small_tow")
    assert np.array_equal(by_path.end, by_name.end)
    with pytest.raises(TypeError, match="simulate: scene must be a Scene"):
        co.simulate(42)
    with pytest.raises(TypeError, match="mpc: scene must be a Scene"):
        co.mpc(3.5, quiet=True)


def test_a_winch_that_turns_nan_later_is_refused_naming_the_winch():
    scene = co.load_scene(MODELS / "small_tow.toml")

    def winch(t, left=None):
        t = np.asarray(t, dtype=float)
        phi = np.where(t > 10.0, np.nan, 0.01 * t)
        return phi, np.full_like(t, 0.01), np.zeros_like(t)

    with pytest.raises(ValueError, match="must return finite angles"):
        co.simulate(scene, winch=winch)
