"""Front doors given the wrong type of argument: a TypeError naming it and what it takes.

Each is refused at entry (no AttributeError from deep inside), before any model is built.
"""

from __future__ import annotations

import pytest

import cable_ocp as co


@pytest.fixture(scope="module")
def scene():
    return co.load_scene("small_tow")


@pytest.mark.parametrize("settings", ["x", 0, "", co.GridSettings()])
def test_mpc_refuses_settings_of_another_kind(scene, settings):
    # 0 and "" are falsy: they used to be replaced by the default settings without a word.
    with pytest.raises(TypeError, match=r"mpc: settings must be an MpcSettings .*; got "):
        co.mpc(scene, settings, quiet=True)


def test_loop_parts_refuses_settings_of_another_kind(scene):
    with pytest.raises(TypeError, match=r"settings must be an MpcSettings .*; got dict"):
        co.control.closed_loop.loop.loop_parts(scene, {"horizon": 10.0})


@pytest.mark.parametrize("run", [None, 42, "run.nc"])
def test_line_run_refuses_what_is_not_a_line_run(run):
    with pytest.raises(TypeError, match=r"line_run: trajectory must be a LineTrajectory .*got "):
        co.plots.line_run(run)


def test_line_run_refuses_a_run_without_a_line():
    run = co.simulate(co.load_scene("hanging", {"numerics.duration": 0.1}), quiet=True)
    with pytest.raises(TypeError, match=r"LineTrajectory \(a run of a scene with \[winch.line\]\); "
                                        r"got Trajectory"):  # fmt: skip
        co.plots.line_run(run)


@pytest.mark.parametrize("run", [42, None, "run.nc"])
def test_animate_refuses_what_is_not_a_run(run):
    with pytest.raises(TypeError, match=r"animate: trajectory must be a Trajectory or a "):
        co.plots.animate(run)


@pytest.mark.parametrize("scene", [None, "small_tow", {"cable": {}}])
def test_cable_model_from_scene_refuses_what_is_not_a_scene(scene):
    with pytest.raises(TypeError, match=r"CableModel.from_scene: scene must be a Scene .*; got "):
        co.CableModel.from_scene(scene)
