"""The safety net's rollout check (issue 42): an action that lets the load wander is handed to
the MPC, the MPC's own action is trusted; its cost per sample is a fraction of a solve's."""

from __future__ import annotations

import numpy as np
import pytest

import cable_ocp as co
from cable_ocp.control.closed_loop.loop import loop_parts
from cable_ocp.control.closed_loop.settings import MpcSettings
from cable_ocp.policy.action import label
from cable_ocp.policy.rollout import RolloutCheck
from cable_ocp.policy.safety import PolicyController
from cable_ocp.scene.bundled import models_dir
from cable_ocp.scene.schema import load_scene


@pytest.fixture(scope="module")
def scene():
    """small_tow over 20 s: with the drum held, drag lifts the end; the MPC pays out."""
    return load_scene(models_dir() / "small_tow.toml").updated({"numerics.duration": 20.0})


class Held:
    """A made-up policy that holds the drum (zero rate), with or without the rollout check."""

    def __init__(self, rollout: bool):
        self.rollout = rollout
        self.name = f"held drum (rollout {rollout})"

    def controller(self, parts):
        network = lambda observations: np.zeros(len(observations))  # noqa: E731
        return PolicyController(parts, network, None, bounds=True, rollout=self.rollout)


def test_the_rollout_hands_over_an_action_that_lets_the_load_wander(scene):
    plain = co.mpc(scene, quiet=True)
    alone = co.mpc(scene, quiet=True, policy=Held(rollout=False))
    netted = co.mpc(scene, quiet=True, policy=Held(rollout=True))
    assert alone.handed_share == 0.0 and alone.omega > 5 * plain.omega
    assert netted.success and 0.0 < netted.handed_share < 1.0
    assert netted.omega <= 1.5 * plain.omega
    handed = [s for s in netted.solves.status if "safety net" in s]
    assert handed and all("predicted Omega over the horizon" in s for s in handed)


def _started(scene, samples: int):
    """A loop's parts after ``samples`` samples of the MPC, and the next sample's inputs."""
    parts = loop_parts(scene, MpcSettings())
    sample = parts.settings.sample
    measured = parts.start()
    for k in range(samples + 1):
        now = k * sample
        winch = parts.command.winch(now, parts.plant.lag)
        estimate = parts.estimator.make_step(measured, *winch)
        if k == samples:
            return parts, now, estimate, winch
        solve = parts.controller.make_step(now, estimate, *winch)
        angle = parts.command.make_step(now, solve, estimate, parts.plant.take_lag())
        measured = parts.plant.make_step(angle, now + sample)


def test_the_check_trusts_the_mpc_s_own_action_and_not_a_far_one(scene):
    parts, now, estimate, (angle, rate) = _started(scene, 4)
    check = RolloutCheck(parts.controller, parts.settings.sample)
    assert check.available
    solve = parts.controller.make_step(now, estimate, angle, rate)  # the MPC's answer here
    own = label(parts.controller.control, solve.parameters, parts.settings.sample)
    assert check.reason(now, estimate, angle, rate, own) == ""
    far = check.reason(now, estimate, angle, rate, own + 0.5)
    assert "predicted Omega over the horizon" in far
    assert check.sweeps == 1 and len(check.seconds) == 2  # one Jacobian served both
