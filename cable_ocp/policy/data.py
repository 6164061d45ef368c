"""The training data: (observation, action) pairs recorded along closed-loop runs, on Dask.

Each scene runs the closed loop (:func:`cable_ocp.mpc`) with a :class:`Recorder` as its
``policy``: at every sample the controller solves (the MPC's answer, whose drum rate over the
next sample is the label, :func:`.action.label`) and the observation is recorded beside it.
In round 0 the MPC's plan drives the plant (its own runs); in a DAgger round (Ross et al. 2011)
the current network's action drives it, so that the pairs are the states the policy itself
visits, labelled by the MPC's solve there. A sample whose label cannot be trusted (the MPC's
solve failed there, or the observation or the label is not finite: a seabed point off the
chart) gives no pair; it is counted and said why (``Recorder.skipped``, the records'
``skipped``), never a crash of the round nor a pair that poisons the fit. :func:`generate` runs
the scenes on the sweep's Dask engine (:func:`cable_ocp.sweep.runner.engine`: a LocalCluster by
default, a scheduler's address for a cluster) and returns the pairs in the scenes' order,
whatever order they finished in.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np

from cable_ocp.control.closed_loop.controller import Solve
from cable_ocp.control.closed_loop.loop import mpc
from cable_ocp.policy.action import label, ramp
from cable_ocp.policy.observation import FEATURES, observe
from cable_ocp.policy.safety import ACTED

SKIPPED_SHOWN = 3  # reasons kept per scene for its samples without a pair


@dataclass
class Pairs:
    """(observation, action) pairs.

    Attributes
    ----------
    observations : array (N, d)
    actions : array (N,), rad/s
    rounds : array (N,) of int
        The DAgger round of each pair.
    """

    observations: np.ndarray
    actions: np.ndarray
    rounds: np.ndarray

    @classmethod
    def empty(cls) -> Pairs:
        """No pairs."""
        return cls(np.zeros((0, len(FEATURES))), np.zeros(0), np.zeros(0, dtype=np.int64))

    def __add__(self, other: Pairs) -> Pairs:
        return Pairs(
            np.vstack([self.observations, other.observations]),
            np.concatenate([self.actions, other.actions]),
            np.concatenate([self.rounds, other.rounds]),
        )


class Recorder:
    """A loop's ``policy`` that records the MPC's label at every sample (module docstring).

    Parameters
    ----------
    network : callable or None
        None: the MPC's plan drives the plant (round 0); else the network's action does.
    """

    name = "data recorder (MPC labels)"

    def __init__(self, network=None):
        self.network = network
        self.observations: list[np.ndarray] = []
        self.actions: list[float] = []
        self.skipped: list[str] = []  # why each sample without a pair gave none

    def controller(self, parts) -> Recorder:
        """The loop's step (this object, bound to the loop's parts)."""
        self.parts = parts
        return self

    def make_step(self, now: float, measured, estimate, angle: float, rate: float) -> Solve:
        """Solve, record the observation and the MPC's label; act as the round says."""
        parts = self.parts
        observation = observe(parts.plant.scene, parts.plant.model, measured, estimate, angle,
                              rate)  # fmt: skip
        solve = parts.controller.make_step(now, estimate, angle, rate)
        sample = parts.settings.sample
        self.record(now, observation, solve, sample)
        if self.network is None:
            return solve
        started = time.perf_counter()
        action = float(self.network(observation[None, :])[0])
        plan = ramp(parts.controller.control, angle, rate, action, sample)
        return replace(solve, parameters=plan, status=ACTED, success=True, by_policy=True,
                       solve_time=time.perf_counter() - started)  # fmt: skip

    def record(self, now: float, observation: np.ndarray, solve: Solve, sample: float) -> None:
        """Keep the sample's pair, or say why it gives none (module docstring)."""
        if not solve.success:
            self.skipped.append(f"t = {now:g} s: the MPC's solve failed ({solve.status})")
            return
        action = label(self.parts.controller.control, solve.parameters, sample)
        bad = [name for name, value in zip(FEATURES, observation, strict=True)
               if not np.isfinite(value)]  # fmt: skip
        if bad or not np.isfinite(action):
            what = f"the observation's {', '.join(bad)}" if bad else "the label"
            self.skipped.append(f"t = {now:g} s: {what} not finite")
            return
        self.observations.append(observation)
        self.actions.append(action)


def run_scene(scene, network=None, round_: int = 0) -> dict:
    """One scene's closed loop with a :class:`Recorder`: its pairs and how the run went.

    The task that :func:`generate` sends to a worker; a scene whose run raises gives no pairs
    and says why. ``skipped`` counts its samples that gave no pair, ``skipped_why`` says why
    (the first :data:`SKIPPED_SHOWN`).
    """
    recorder = Recorder(network)
    try:
        result = mpc(scene, quiet=True, policy=recorder)
        success, omega, status = result.success, result.omega, result.status
    except Exception as error:  # noqa: BLE001 - a failed scene is a record, not a crash
        success, omega, status = False, float("nan"), f"{type(error).__name__}: {error}"
    count = len(recorder.actions)
    return {
        "observations": np.array(recorder.observations).reshape(count, len(FEATURES)),
        "actions": np.array(recorder.actions, dtype=float),
        "rounds": np.full(count, round_, dtype=np.int64),
        "success": success,
        "omega": omega,
        "status": status,
        "skipped": len(recorder.skipped),
        "skipped_why": recorder.skipped[:SKIPPED_SHOWN],
    }


def generate(
    scenes: list,
    network=None,
    round_: int = 0,
    scheduler: str | None = None,
    workers: int | None = None,
    progress=None,
) -> tuple[Pairs, list[dict]]:
    """Run the scenes on the Dask engine; their pairs (in the scenes' order) and records.

    Parameters
    ----------
    scenes : list of Scene
    network : callable, optional
        The current policy's network (a DAgger round); None: the MPC drives (round 0).
    round_ : int
        The round's number, kept with each pair.
    scheduler : str, optional
        A Dask scheduler's address (``tcp://host:8786``); None: a LocalCluster on this machine.
    workers : int, optional
        The LocalCluster's workers (None: one per core).
    progress : callable, optional
        Called with the count of scenes done, as each finishes.
    """
    from cable_ocp.sweep.runner import mapped

    tasks = [(scene, network, round_) for scene in scenes]
    records = mapped(run_scene, tasks, scheduler, workers, progress)
    pairs = Pairs.empty()
    for record in records:
        pairs = pairs + Pairs(record["observations"], record["actions"], record["rounds"])
    kept = ("success", "omega", "status", "skipped", "skipped_why")
    summaries = [{key: record[key] for key in kept} for record in records]
    return pairs, summaries
