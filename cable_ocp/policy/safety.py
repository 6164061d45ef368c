"""The safety net: at every sample, trust the policy's action or hand the sample to the MPC.

Three checks, cheap beside a solve, decide (Zhang, Bujarbaruah and Borrelli 2019: a check of each
action, the MPC when it fails):

1. **The envelope.** Every feature of the observation lies inside the range the training data
   spanned, widened by ``margin`` of that range on each side (:class:`Envelope`). A network
   extrapolates without warning; a scene outside the family (a faster tow, a higher sea) shows
   up here, and is handed over, never silently controlled.
2. **The bounds.** The plan the action makes (:func:`.action.ramp`) keeps, over the next
   sample, the controller's winch bounds as the MPC's solve must: the angle range narrowed by
   the heave feedback's room, the rate and acceleration limits.
3. **The rollout.** The controller's reduced model runs one horizon from the estimate; the
   policy's action, followed by the best plan after it, must predict an Omega over the horizon
   within a margin of the MPC's own prediction, and keep the minimum clearance
   (:mod:`cable_ocp.policy.rollout`). The envelope and the bounds cannot see an action that
   keeps the plant alive but lets the load wander; the rollout does.

Where any fails, the controller solves the sample (:meth:`PolicyController.make_step`), and
its solve's status says why it was handed over.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np

from cable_ocp.control.closed_loop.controller import Solve
from cable_ocp.policy.action import ramp
from cable_ocp.policy.observation import FEATURES, UNITS, observe
from cable_ocp.policy.rollout import RolloutCheck

# Share of each feature's training range by which the envelope is widened on each side.
MARGIN = 0.05
# rad, rad/s, rad/s^2: a plan beyond its bounds by less than this keeps them (round-off).
BOUND_TOLERANCE = 1e-9
ACTED = "policy"  # the status of a sample the policy acted at


@dataclass(frozen=True)
class Envelope:
    """The training data's range of each feature, widened by ``margin`` of it on each side.

    Attributes
    ----------
    low, high : arrays (d,), the features' units
    margin : float
    """

    low: np.ndarray
    high: np.ndarray
    margin: float = MARGIN

    @classmethod
    def of(cls, observations: np.ndarray, margin: float = MARGIN) -> Envelope:
        """The envelope of training observations (N, d)."""
        return cls(observations.min(axis=0), observations.max(axis=0), margin)

    def outside(self, observation: np.ndarray) -> str:
        """Why an observation lies outside the envelope (empty when it lies inside).

        A NaN feature (a seabed point off the chart) is outside.
        """
        width = self.high - self.low
        slack = self.margin * width + 1e-9 * np.maximum(1.0, np.abs(self.high))
        low, high = self.low - slack, self.high + slack
        bad = ~((observation >= low) & (observation <= high))
        if not bad.any():
            return ""
        k = int(np.argmax(bad))
        return (
            f"{FEATURES[k]} = {observation[k]:.4g} {UNITS[k]} outside the training envelope "
            f"[{low[k]:.4g}, {high[k]:.4g}]"
        )


class PolicyController:
    """A closed loop's step run by a policy with the MPC as its safety net.

    Parameters
    ----------
    parts : LoopParts
        The loop's parts (:func:`~cable_ocp.control.closed_loop.loop.loop_parts`): its
        controller solves where the net hands a sample over.
    network : callable
        Observation (d,) -> drum rate (rad/s), e.g. :class:`.network.Network`.
    envelope : Envelope or None
        None: no envelope check (the policy without its net).
    bounds : bool
        Check the plan's bounds (False: the policy's action whatever it gives, the plant's
        limiter and drum clipping it as they clip any command).
    rollout : bool
        Check the action on the reduced model's rollout (the module docstring's third check;
        made where the controller's solver has an RK4 map to roll out on, Gauss-Newton's).
    """

    def __init__(
        self, parts, network, envelope: Envelope | None, bounds: bool = True, rollout: bool = True
    ):
        self.parts, self.network, self.envelope = parts, network, envelope
        self.bounds = bounds
        self.scene = parts.plant.scene
        self.sample = parts.settings.sample
        self.check = RolloutCheck(parts.controller, self.sample) if rollout else None

    def observe(self, measured, estimate, angle: float, rate: float) -> np.ndarray:
        """The observation at this sample (:func:`.observation.observe`)."""
        return observe(self.scene, self.parts.plant.model, measured, estimate, angle, rate)

    def action(self, now: float, observation: np.ndarray, estimate, angle: float, rate: float):
        """The policy's plan at the sample ``now`` (s) and why to hand it over (empty: trusted)."""
        reason = self.envelope.outside(observation) if self.envelope is not None else ""
        rate_command = float(self.network(observation[None, :])[0])
        control = self.parts.controller.control
        plan = ramp(control, angle, rate, rate_command, self.sample)
        if not reason and self.bounds:
            bounds = self.parts.controller.problem.bounds
            lower, upper = bounds.narrowed(estimate.margin, self.sample)
            excess = bounds.excess(plan, lower, upper, rows=bounds.starts < self.sample - 1e-9)
            if excess > BOUND_TOLERANCE:
                reason = f"its plan leaves the winch bounds by {excess:.3g} over the next sample"
        if not reason and self.check is not None and self.check.available:
            reason = self.check.reason(now, estimate, angle, rate, rate_command)
        return plan, reason

    def make_step(self, now: float, measured, estimate, angle: float, rate: float) -> Solve:
        """The sample's plan: the policy's where trusted, else the controller's solve."""
        started = time.perf_counter()
        observation = self.observe(measured, estimate, angle, rate)
        plan, reason = self.action(now, observation, estimate, angle, rate)
        if not reason:
            return Solve(plan, ACTED, True, 0, time.perf_counter() - started, by_policy=True)
        solve = self.parts.controller.make_step(now, estimate, angle, rate)
        return replace(solve, status=f"{solve.status} (safety net: {reason})")
