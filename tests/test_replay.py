"""A result reproduces its run from its file: the scene it ran is kept in it, and an optimum is
replayed by ``simulate(scene, winch=result)``. The reference is the saved run itself: a replay
that drives the model otherwise (a node off its step, a feedforward left out) differs from it by
far more than the 1e-9 m asked."""

from __future__ import annotations

import numpy as np
import pytest

import cable_ocp as co
from cable_ocp import cli
from cable_ocp.control.closed_loop import MpcSettings
from cable_ocp.drive.winch import RETIMES
from cable_ocp.scene.bundled import scene_path

HEAVE = {"top.heave.amplitude": 0.5, "top.heave.period": 8.0}


@pytest.fixture(scope="module")
def heaving_optimum(tmp_path_factory):
    """small_tow with a heave (the optimum rides on its feedforward), saved and loaded."""
    scene = co.load_scene(scene_path("small_tow"), HEAVE)
    result = co.optimize(scene, quiet=True)
    assert result.success and result.heave_feedforward, result.status
    folder = tmp_path_factory.mktemp("optimum")
    result.save(folder)
    return scene, result, co.load_result(folder)


def test_an_optimum_replays_from_its_file_on_its_own_scene(heaving_optimum):
    _, result, loaded = heaving_optimum
    replay = co.simulate(loaded.scene, winch=loaded, compiled=True)
    assert abs(replay.omega - result.omega) < 1e-9
    np.testing.assert_allclose(replay.end, result.trajectory.end, atol=1e-9)


def test_an_optimum_replays_on_the_users_scene_with_its_feedforward(heaving_optimum):
    """The user's scene does not compensate the heave: the replay adds eq. 38 as the
    optimisation did; without it the end moves with the heave and Omega is far off."""
    scene, result, loaded = heaving_optimum
    assert not scene.top.heave_compensated and loaded.scene.top.heave_compensated
    replay = co.simulate(scene, winch=loaded, compiled=True)
    assert abs(replay.omega - result.omega) < 1e-9
    slow = co.simulate(scene, winch=loaded.winch_profile(loaded.scene), compiled=True)
    assert abs(slow.omega - result.omega) > 1e-3


def test_the_profile_samples_at_any_time(heaving_optimum):
    """``winch_angle(t)`` is the verified run's angle at its output times, and between them the
    cubic Hermite interpolation of the run's angle and pay-out rate (error O(h^4))."""
    from scipy.interpolate import CubicHermiteSpline

    from cable_ocp.model.layout import INPUTS

    scene, result, loaded = heaving_optimum
    run = result.trajectory
    np.testing.assert_allclose(loaded.winch_angle(run.time), run.winch_angle, atol=1e-12)
    rate = run.inputs[:, INPUTS.top_length_rate] / scene.winch.drum_radius
    between = 0.5 * (run.time[1:] + run.time[:-1])
    interpolated = CubicHermiteSpline(run.time, run.winch_angle, rate)(between)
    np.testing.assert_allclose(loaded.winch_angle(between), interpolated, atol=1e-4)


def test_an_optimum_on_a_fitted_step_replays_at_that_step(tmp_path):
    """T = 37 s at h = 0.25 s: the verification ran at a shorter step (the nodes on its step
    ends); the file's scene holds that step, so the replay is the verified run."""
    scene = co.load_scene(scene_path("small_tow"), {"numerics.duration": 37.0})
    result = co.optimize(scene, quiet=True)
    assert result.success, result.status
    result.save(tmp_path)
    loaded = co.load_result(tmp_path / "result.nc")
    assert loaded.scene.numerics.step == pytest.approx(result.verified_step, rel=1e-12)
    assert loaded.scene.numerics.step < scene.numerics.step
    replay = co.simulate(loaded.scene, winch=loaded, compiled=True)
    assert abs(replay.omega - result.omega) < 1e-9


def test_a_simulation_keeps_its_scene(tmp_path):
    scene = co.load_scene(scene_path("hanging"), {"numerics.duration": 2.0})
    run = co.simulate(scene)
    run.save(tmp_path / "trajectory")
    loaded = co.load_result(tmp_path)
    assert loaded.scene == scene
    assert co.simulate(loaded.scene).omega == run.omega


def test_an_mpc_run_with_a_heave_set_on_the_command_line_reruns_from_its_file(tmp_path, capsys):
    """``--set`` overrides are in mpc.nc's scene and its settings in its record: the loop on
    them gives the same Omega (1e-9 m), and the same plant run."""
    out = tmp_path / "m"
    command = ["mpc", "small_tow", "--out", str(out), "--quiet",
               "--set", "top.heave.amplitude=0.5", "--set", "top.heave.period=8.0"]  # fmt: skip
    assert cli.main(command) in (0, 3), capsys.readouterr().err
    loaded = co.load_result(out)
    assert isinstance(loaded, co.MpcResult)
    assert loaded.scene == co.load_scene(scene_path("small_tow"), HEAVE)
    again = co.mpc(loaded.scene, MpcSettings.from_record(loaded.settings), quiet=True)
    assert abs(again.omega - loaded.omega) < 1e-9
    np.testing.assert_allclose(again.end, loaded.end, atol=1e-9)


def test_a_result_written_before_scenes_were_kept_loads_and_says_so(heaving_optimum, tmp_path):
    from dataclasses import replace

    _, result, _ = heaving_optimum
    replace(result, scene_record={}).save(tmp_path)
    old = co.load_result(tmp_path)
    assert old.scene_record == {} and old.omega == result.omega
    with pytest.raises(ValueError, match="holds no scene .* load the scene file instead"):
        _ = old.scene


def test_a_folder_without_a_result_is_named(tmp_path):
    with pytest.raises(ValueError, match="no cable_ocp result there"):
        co.load_result(tmp_path)


def test_cable_ocp_replay_drives_a_saved_optimum_on_its_scene_or_a_changed_one(
    heaving_optimum, tmp_path, capsys
):
    """``cable-ocp replay FOLDER``: the saved scene and profile give the saved Omega again
    (1e-9 m); ``--set`` changes the scene (a finer model keeps the profile and moves Omega)."""
    import json

    scene, result, loaded = heaving_optimum
    folder = tmp_path / "optimum"
    result.save(folder)
    assert cli.main(["replay", str(folder), "--out", str(tmp_path / "same"), "--quiet"]) == 0
    same = json.loads((tmp_path / "same" / "summary.json").read_text())
    assert abs(same["omega"] - result.omega) < 1e-9
    assert same["saved_omega"] == result.omega and same["units"]["omega"] == "m"
    assert (tmp_path / "same" / "clearance.png").is_file()
    finer = ["replay", str(folder), "--out", str(tmp_path / "finer"), "--quiet"]
    assert cli.main([*finer, "--set", "model.elements=8"]) == 0
    moved = json.loads((tmp_path / "finer" / "summary.json").read_text())
    assert np.isfinite(moved["omega"]) and moved["omega"] != same["omega"]
    capsys.readouterr()


def test_cable_ocp_replay_refuses_what_is_not_an_optimum(tmp_path, capsys):
    run = co.simulate(co.load_scene(scene_path("small_tow")), compiled=True)
    (tmp_path / "run").mkdir()
    run.save(tmp_path / "run" / "trajectory")
    code = cli.main(["replay", str(tmp_path / "run"), "--out", str(tmp_path / "o"), "--quiet"])
    assert code == 2
    err = capsys.readouterr().err
    assert "holds a Trajectory, a run whose winch is not kept as a profile to drive" in err
    assert "replay takes what optimize or mpc saved" in err and err.count("\n") == 1
    assert not (tmp_path / "o").exists()


@pytest.fixture(scope="module")
def short_optimum(tmp_path_factory):
    """A 10 s optimum of small_tow, saved by the command line."""
    folder = tmp_path_factory.mktemp("short") / "optimum"
    assert cli.main(["optimize", "small_tow", "--set", "numerics.duration=10", "--quiet",
                     "--out", str(folder)]) == 0  # fmt: skip
    return folder


def test_cable_ocp_replay_on_another_duration_is_refused_naming_retime(
    short_optimum, tmp_path, capsys, monkeypatch
):
    """Issue 45 item 3 on the command line: the refusal names the option that chooses, before
    any work (it named the API's result.retimed)."""
    from cable_ocp.simulation import run

    monkeypatch.setattr(run, "simulate", lambda *a, **k: pytest.fail("refused before any work"))
    out = tmp_path / "o"
    code = cli.main(["replay", str(short_optimum), "--set", "numerics.duration=25",
                     "--out", str(out), "--quiet"])  # fmt: skip
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1, err
    assert "numerics.duration = 25 s, but the winch profile was made for 10 s" in err
    assert "--retime 'hold': played in its own time" in err and "retimed(" not in err
    assert not out.exists()


@pytest.mark.parametrize("retime", ["hold", "stretch"])
def test_cable_ocp_replay_retimes_by_the_users_choice_and_says_so(
    short_optimum, tmp_path, capsys, retime
):
    import json

    out = tmp_path / retime
    code = cli.main(["replay", str(short_optimum), "--set", "numerics.duration=25", "--retime",
                     retime, "--out", str(out), "--quiet"])  # fmt: skip
    printed = capsys.readouterr().out
    assert code == 0
    assert f"note: the 10 s optimum {RETIMES[retime]}, on a 25 s scene" in printed
    summary = json.loads((out / "summary.json").read_text())
    assert summary["saved_omega"] > 0
    assert summary["retimed"] == f"the 10 s optimum {RETIMES[retime]}, on a 25 s scene"
    assert co.load_result(out).time[-1] == pytest.approx(25.0)


def test_cable_ocp_replay_drives_a_closed_loops_winch(tmp_path, capsys):
    """An mpc.nc replays too: the plant's run again from the applied winch (to 1 mm, as the
    API's simulate(scene, winch=MpcResult)), its Omega beside the saved one."""
    import json

    loop = tmp_path / "loop"
    assert cli.main(["mpc", "small_tow", "--set", "numerics.duration=10", "--quiet",
                     "--out", str(loop)]) == 0  # fmt: skip
    out = tmp_path / "replayed"
    assert cli.main(["replay", str(loop), "--out", str(out), "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    saved = co.load_result(loop)
    assert summary["saved_omega"] == saved.omega
    assert summary["omega"] == pytest.approx(saved.omega, rel=0.05)
    np.testing.assert_allclose(co.load_result(out).end, saved.trajectory.end, atol=1e-3)
    capsys.readouterr()


@pytest.mark.parametrize("given", ["folder", "file", "parent"])
def test_cable_ocp_replay_never_writes_over_its_source(heaving_optimum, tmp_path, capsys, given):
    """``--out`` the optimum's folder (given as its folder or its result.nc), or a folder that
    holds it, is refused before any work: the replay's run would replace the optimum."""
    _, result, _ = heaving_optimum
    parent = tmp_path / "runs"
    folder = parent / "optimum"
    result.save(folder)
    for results in (parent, folder):  # results folders (as optimize --out writes), replaceable
        (results / ".cable_ocp-results").write_text("")
    before = {p.name: p.read_bytes() for p in folder.iterdir()}
    source = {"folder": folder, "file": folder / "result.nc", "parent": folder}[given]
    out = parent if given == "parent" else folder
    code = cli.main(["replay", str(source), "--out", str(out), "--quiet"])
    assert code == 2
    assert "is the folder replay reads" in capsys.readouterr().err
    assert {p.name: p.read_bytes() for p in folder.iterdir()} == before


def test_cable_ocp_replay_runs_the_compiled_model_as_simulate_does(
    heaving_optimum, tmp_path, capsys, monkeypatch
):
    """A replay on a finer model ran the interpreted one (issue 45 item 9: n = 150 took 32 s
    against 15 s compiled); --interpreted asks for it."""
    from cable_ocp.simulation import run

    _, result, _ = heaving_optimum
    result.save(tmp_path / "optimum")
    seen = []

    def recorded(scene, winch=None, quiet=True, compiled=False, **kwargs):
        seen.append(compiled)
        raise KeyboardInterrupt  # enough: the call was made

    monkeypatch.setattr(run, "simulate", recorded)
    command = ["replay", str(tmp_path / "optimum"), "--quiet"]
    assert cli.main([*command, "--out", str(tmp_path / "a")]) == 130
    assert cli.main([*command, "--interpreted", "--out", str(tmp_path / "b")]) == 130
    assert seen == [True, False]
    capsys.readouterr()


def test_cable_ocp_replay_drives_a_saved_landing_plan(tmp_path, capsys):
    """A LandingPlan saved by the API replays on the command line: the same line run again (its
    end to 1e-9 m, as co.simulate(plan.scene, winch=plan)); a plan keeps its own time, so
    --retime is refused naming why."""
    from test_lowering import lowering_scene

    plan = co.plan_landing(lowering_scene(), quiet=True)
    assert plan.run is not None, plan.status
    path = plan.save(tmp_path / "plan.nc")
    out = tmp_path / "replayed"
    code = cli.main(["replay", str(path), "--out", str(out), "--quiet"])
    assert code == 0, capsys.readouterr().err
    np.testing.assert_allclose(co.load_result(out).end, plan.run.end, rtol=0, atol=1e-9)
    code = cli.main(["replay", str(path), "--retime", "hold", "--out", str(tmp_path / "r")])
    assert code == 2
    assert "--retime hold: a LandingPlan replays in its own time" in capsys.readouterr().err
