"""Learning a policy (issue 42): data on a LocalCluster of 2 workers, the same seed the same
policy, the policy in the closed loop with its safety net, a scene outside the family flagged."""

from __future__ import annotations

import shutil

import numpy as np
import pytest

import cable_ocp as co
from cable_ocp.policy.data import generate, run_scene
from cable_ocp.policy.family import load_family
from cable_ocp.policy.observation import FEATURES
from cable_ocp.scene.bundled import models_dir

FAMILY = """
name = "tiny_tow"
scene = "{scene}"
[set]
"numerics.duration" = 20.0
[ranges]
"top.tow.surge_speed" = [0.8, 1.1]
"top.heave.amplitude" = [0.0, 0.4]
"top.heave.period" = [6.0, 9.0]
"""


@pytest.fixture(scope="module")
def family_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("family") / "tiny_tow.toml"
    path.write_text(FAMILY.format(scene=models_dir() / "small_tow.toml"))
    return path


@pytest.fixture(scope="module")
def learned(family_file, tmp_path_factory):
    out = tmp_path_factory.mktemp("learned")
    policy = co.learn_policy(
        family_file, out=out, scenes=3, rounds=1, hidden=(6,), seed=4, workers=2, quiet=True
    )
    return policy, out


def test_data_on_a_local_cluster_of_two_workers_is_the_runs_in_order(family_file):
    scenes = load_family(family_file).draw(3, seed=1)
    pairs, records = generate(scenes, workers=2)
    alone = [run_scene(scene) for scene in scenes]  # here, one after the other
    np.testing.assert_array_equal(pairs.observations, np.vstack([r["observations"] for r in alone]))
    np.testing.assert_array_equal(pairs.actions, np.concatenate([r["actions"] for r in alone]))
    assert pairs.observations.shape == (3 * 20, len(FEATURES))  # one pair a 1 s sample
    assert all(record["success"] for record in records)
    assert np.ptp(pairs.actions) > 0  # the MPC moved the winch


def test_the_same_seed_learns_the_same_policy_bit_for_bit(family_file, learned):
    policy, out = learned
    again = co.learn_policy(
        family_file, scenes=3, rounds=1, hidden=(6,), seed=4, workers=2, quiet=True
    )
    assert again.digest == policy.digest
    np.testing.assert_array_equal(again.observations, policy.observations)
    assert set(np.unique(policy.rounds)) == {0, 1}  # the MPC's runs and one DAgger round
    for round_ in policy.validation["training"]["rounds"]:  # 3 scenes of 20 samples: every
        assert round_["pairs"] + round_["samples_skipped"] == 60  # sample a pair or counted
    saved = co.load_policy(out / "policy.nc", family=family_file)
    assert saved.digest == policy.digest
    assert (out / "policy.c").is_file() and (out / "policy.h").is_file()


def test_the_policy_runs_the_loop_and_its_result_says_so(family_file, learned, tmp_path):
    policy, _ = learned
    scene = load_family(family_file).draw(2, seed=99)[0]  # a scene training never saw
    alone = co.mpc(scene, quiet=True, policy=policy.alone())
    assert alone.solves.by_policy.all() and alone.handed_share == 0.0
    assert alone.settings["policy"] == policy.alone().name
    assert "the policy acted at 20 of 20 samples" in alone.status
    netted = co.mpc(scene, quiet=True, policy=policy)
    assert 0.0 <= netted.handed_share < 1.0
    again = co.MpcResult.load(netted.save(tmp_path / "mpc"))
    np.testing.assert_array_equal(again.solves.by_policy, netted.solves.by_policy)
    assert again.handed_share == netted.handed_share
    plain = co.mpc(scene, quiet=True)
    assert not plain.solves.by_policy.any() and np.isnan(plain.handed_share)


def test_a_scene_outside_the_family_is_flagged_by_the_safety_net(family_file, learned):
    policy, _ = learned
    scene = load_family(family_file).base.updated({"top.tow.surge_speed": 1.6})
    result = co.mpc(scene, quiet=True, policy=policy)
    assert result.handed_share > 0.5
    flagged = [status for status in result.solves.status if "safety net" in status]
    assert any("tow_speed" in s and "outside the training envelope" in s for s in flagged)
    assert "the MPC at" in result.status


def test_mpc_refuses_a_policy_that_is_not_one():
    with pytest.raises(TypeError, match="policy must be a learned policy"):
        co.mpc("small_tow", policy="policy.nc")


def test_cable_ocp_learn_writes_the_policy_and_mpc_runs_it(family_file, learned, tmp_path, capsys):
    import json

    from cable_ocp.cli import main

    out = tmp_path / "learned"
    command = ["learn", str(family_file), "--out", str(out), "--scenes", "2", "--rounds", "0",
               "--workers", "2", "--hidden", "4", "--quiet"]  # fmt: skip
    assert main(command) == 0
    policy = co.load_policy(out / "policy.nc", family=family_file)
    assert policy.network.hidden == (4,) and set(policy.rounds) == {0}
    assert json.loads((out / "summary.json").read_text())["pairs"] == 40
    assert (out / "policy.c").is_file()
    _, saved = learned
    run = tmp_path / "mpc"
    assert main(["mpc", "small_tow", "--out", str(run), "--set", "numerics.duration=20",
                 "--policy", str(saved / "policy.nc"), "--quiet"]) == 0  # fmt: skip
    summary = json.loads((run / "summary.json").read_text())
    assert 0.0 <= summary["handed_share"] < 1.0 and summary["units"]["handed_share"] == "1"


def test_cable_ocp_learn_refuses_bad_input_before_any_work(tmp_path, capsys):
    from cable_ocp.cli import main

    out = tmp_path / "nothing"
    assert main(["learn", "no_such_family", "--out", str(out), "--quiet"]) == 2
    assert "no_such_family" in capsys.readouterr().err and not out.exists()
    assert main(["learn", "hill_tow", "--out", str(out), "--hidden", "0,4"]) == 2
    not_a_policy = tmp_path / "policy.nc"
    not_a_policy.write_text("not netCDF")
    assert main(["mpc", "small_tow", "--out", str(out), "--policy", str(not_a_policy)]) == 2
    assert "policy.nc: not a readable netCDF file" in capsys.readouterr().err
    assert main(["bench", "--only", "policy"]) == 2  # which policy to time is not said
    assert "give --policy POLICY.nc" in capsys.readouterr().err


@pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler")
def test_the_policy_bench_times_the_c_function_beside_the_mpc(learned, capsys):
    from cable_ocp.policy.bench import bench_policy

    policy, _ = learned
    figures = bench_policy(policy, co.load_scene("small_tow", {"numerics.duration": 20.0}))
    assert 0 < figures["c_per_sample"] < 20e-6  # the bound on a sample's evaluation
    assert figures["ratio"] == figures["mpc_median_solve"] / figures["c_per_sample"]
    assert 0 < figures["rollout_check_median"] < 10 * figures["mpc_median_solve"]
    assert 0.0 <= figures["handed_share"] <= 1.0
    out = capsys.readouterr().out
    assert "us per sample" in out and "rollout check" in out and "Jacobian sweeps" in out


def test_the_validation_runs_held_out_scenes_and_states_its_bound(family_file, learned):
    from cable_ocp.policy.validation import statement, success_bound, validate_policy

    policy, _ = learned
    # A chunk of a longer validation: scenes 1 and 2 of the 3 drawn.
    figures = validate_policy(
        policy, family_file, scenes=3, workers=2, quiet=True, indices=range(1, 3)
    )
    assert figures["scenes"] == 2 and [row["scene"] for row in figures["rows"]] == [1, 2]
    for kind in ("alone", "net"):
        successes = figures[kind]["successes"]
        assert figures[kind]["statement"] == statement(2, 2 - successes)
    assert 0.0 <= figures["net"]["handed_share"] <= 1.0
    assert np.isfinite(figures["locked"]["median_omega"])
    assert success_bound(100, 0) == pytest.approx(0.05 ** (1 / 100))  # the all-success case
    assert success_bound(10, 10) == 0.0


@pytest.mark.parametrize("indices", [range(2, 5), range(3, 3), [0, 1], range(-1, 2)])
def test_a_validation_chunk_outside_the_scenes_drawn_is_refused_before_any_run(indices):
    from cable_ocp.policy.validation import validate_policy

    with pytest.raises(ValueError, match=r"indices = .*within range\(3\)"):
        validate_policy(None, "no_such_family", scenes=3, indices=indices)


def test_the_observation_is_what_the_winch_controller_measures():
    """Each feature against the measurement it comes from, on a tow towards a hill."""
    from cable_ocp.control.closed_loop import loop_parts
    from cable_ocp.control.closed_loop.drum import ON_COMMAND
    from cable_ocp.model.layout import INPUTS
    from cable_ocp.policy.observation import LOOK_AHEAD, observe
    from cable_ocp.simulation.seabed import seabed_height

    hill = {"height": 4.0, "x0": 30.0, "y0": 0.0, "width_x": 10.0, "width_y": 10.0}
    overrides = {"numerics.duration": 20.0, "seabed.hills": [hill], "top.heave.amplitude": 0.3,
                 "top.heave.period": 7.0}  # fmt: skip
    scene = co.load_scene("small_tow", overrides)
    parts = loop_parts(scene, co.MpcSettings())
    measured = parts.start()
    for k in range(3):  # three samples under the MPC
        now = k * parts.settings.sample
        winch = parts.command.winch(now, parts.plant.lag)
        estimate = parts.estimator.make_step(measured, *winch)
        solve = parts.controller.make_step(now, estimate, *winch)
        parts.command.make_step(now, solve, estimate, ON_COMMAND)
        measured = parts.plant.make_step(parts.command.angle, now + parts.settings.sample)
    winch = parts.command.winch(3.0, parts.plant.lag)
    estimate = parts.estimator.make_step(measured, *winch)
    observation = observe(scene, parts.plant.model, measured, estimate, *winch)
    seen = dict(zip(FEATURES, observation, strict=True))
    x, u = measured.states[-1], measured.inputs[-1]
    assert (seen["drum_angle"], seen["drum_rate"]) == winch
    assert seen["heave"] == u[INPUTS.top][2] and seen["heave_rate"] == u[INPUTS.top_velocity][2]
    assert seen["tow_speed"] == pytest.approx(np.hypot(*u[INPUTS.top_velocity][:2]))
    assert 0 < seen["tension"] < 1e6  # the rope pulls at the top (N)
    under = seabed_height(scene.seabed, x[0], x[1])
    assert seen["clearance_error"] == pytest.approx(x[2] - under - estimate.reference)
    track = u[INPUTS.top_velocity][:2] / np.hypot(*u[INPUTS.top_velocity][:2])
    for distance in LOOK_AHEAD:
        point = x[:2] + distance * track
        expected = seabed_height(scene.seabed, *point) - under
        assert seen[f"seabed_ahead_{distance:g}m"] == pytest.approx(expected)
    assert seen["seabed_ahead_30m"] > seen["seabed_ahead_5m"] > 0  # the hill ahead rises
