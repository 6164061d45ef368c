"""The DAgger data's honesty (issue 42): a sample whose MPC label failed, or whose observation
is not finite, gives no pair; it is counted and said why, and the round goes on."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from cable_ocp.control.closed_loop.controller import Solve
from cable_ocp.drive.controls import HermiteIntervals
from cable_ocp.policy.action import ramp
from cable_ocp.policy.data import Recorder
from cable_ocp.policy.network import Network
from cable_ocp.policy.observation import FEATURES

CONTROL = HermiteIntervals(20.0, 4, free_start=True)


def _recorder() -> Recorder:
    recorder = Recorder()
    recorder.parts = SimpleNamespace(controller=SimpleNamespace(control=CONTROL))
    return recorder


def _observation(**nan) -> np.ndarray:
    observation = np.arange(1.0, len(FEATURES) + 1.0)
    for name in nan:
        observation[FEATURES.index(name)] = np.nan
    return observation


def test_a_failed_label_or_a_non_finite_observation_gives_no_pair_and_says_why():
    recorder = _recorder()
    good = Solve(ramp(CONTROL, 0.1, 0.0, 0.25, 1.0), "1 Gauss-Newton step(s)", True, 1, 1e-3)
    failed = Solve(good.parameters, "the QP failed: DAQP exit flag -1", False, 1, 1e-3)
    nan_plan = Solve(np.full(CONTROL.size, np.nan), "1 Gauss-Newton step(s)", True, 1, 1e-3)
    off_chart = FEATURES[-2]  # a seabed point ahead (NaN off the chart)
    recorder.record(0.0, _observation(), good, 1.0)
    recorder.record(1.0, _observation(), failed, 1.0)
    recorder.record(2.0, _observation(**{off_chart: True}), good, 1.0)
    recorder.record(3.0, _observation(), nan_plan, 1.0)
    recorder.record(4.0, _observation(), good, 1.0)
    assert len(recorder.actions) == 2 and np.allclose(recorder.actions, 0.25)
    assert len(recorder.skipped) == 3
    assert recorder.skipped[0].startswith("t = 1 s: the MPC's solve failed")
    assert "DAQP exit flag -1" in recorder.skipped[0]
    assert recorder.skipped[1] == f"t = 2 s: the observation's {off_chart} not finite"
    assert recorder.skipped[2] == "t = 3 s: the label not finite"
    # What was kept fits (a non-finite pair would make Network.fit refuse the whole round).
    x = np.array(recorder.observations + [_observation() + 1.0])
    network, _ = Network.fit(x, np.array(recorder.actions + [0.3]), (2,), 1.0, 0, iterations=5)
    assert np.isfinite(network(x)).all()
