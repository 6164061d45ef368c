"""The winch angle the closed loop commands: the plan in force and the heave feedback.

:class:`Plan` is one solve's plan, blended into from the one before; :class:`WinchCommand` keeps
the plan in force and the heave reference across the samples and gives the angle history a
plant runs under (:meth:`WinchCommand.make_step`), the measured heave's pay-out added (eq. 38 on
the measured motion, about the forecast the controller planned with) when the settings ask for
the heave feedback.
"""

from __future__ import annotations

import numpy as np

from cable_ocp.control.closed_loop.controller import Estimate, Solve
from cable_ocp.control.closed_loop.drum import ON_COMMAND, Lag
from cable_ocp.control.closed_loop.forecast import BlendedHeight, TopForecast
from cable_ocp.control.closed_loop.settings import MpcSettings
from cable_ocp.drive.controls import HermiteIntervals
from cable_ocp.drive.winch import heave_payout


class Plan:
    """The plan in force: the controller's parameters from the solve at ``start`` (s).

    A new plan starts at the winch's angle and rate (its first node is held there) but not at
    its acceleration: over its first ``blend`` seconds (one RK4 step of the controller's model)
    it takes over from the ``previous`` one by the quintic smoothstep, as the heave reference
    does (:class:`.forecast.BlendedHeight`), so that the top element's acceleration never jumps
    at a sample (with it, one of the 5 heaving robustness scenes whose plant's bonds opened ran
    through; a wider limiter band did the rest, ``MpcSettings.limiter_band``).
    """

    def __init__(
        self,
        start: float,
        parameters: np.ndarray,
        control: HermiteIntervals,
        previous: Plan | None = None,
        blend: float = 0.0,
    ):
        self.start, self.parameters, self.control = start, parameters, control
        self.previous, self.blend = previous, blend

    def __call__(self, t: np.ndarray, left=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Angle, rate and acceleration (rad, rad/s, rad/s^2) at the times ``t``."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        new = self.control.evaluate(self.parameters, t - self.start, left)
        if self.previous is None or self.blend <= 0:
            return tuple(new)
        tau = ((t - self.start) / self.blend).clip(0.0, 1.0)
        # Past the blend (tau = 1) the predecessor's weights are zero: it is evaluated only
        # where it still counts, most of a sample's times being past it.
        blending = tau < 1.0
        if not blending.any():
            return tuple(new)
        if left is not None and np.ndim(left) > 0:
            left = np.asarray(left)[blending]
        old = self.previous(t[blending], left)
        tau = tau[blending]
        keep = 1 - tau**3 * (10 - 15 * tau + 6 * tau**2)
        keep_rate = -30 * tau**2 * (1 - tau) ** 2 / self.blend
        keep_acc = -(60 * tau - 180 * tau**2 + 120 * tau**3) / self.blend**2
        here = [values[blending] for values in new]
        angle, rate, acceleration = new  # the evaluation's own rows, written over in place
        gap = [o - n for o, n in zip(old, here, strict=True)]
        angle[blending] = here[0] + keep * gap[0]
        rate[blending] = here[1] + keep * gap[1] + keep_rate * gap[0]
        acceleration[blending] = (
            here[2] + keep * gap[2] + 2 * keep_rate * gap[1] + keep_acc * gap[0]
        )
        return angle, rate, acceleration

    def settled(self) -> Plan:
        """The same plan without its predecessor (once the blend is over)."""
        return Plan(self.start, self.parameters, self.control)


class Shifted:
    """A plan moved by the drum's angle lag at ``start`` (s), as the plan before a new one.

    A new plan starts at the drum's angle (:meth:`WinchCommand.winch` with the lag), so the one
    it takes over from is the old plan moved by the lag's angle.
    """

    def __init__(self, plan: Plan, start: float, lag: Lag):
        self.plan, self.start, self.lag = plan, start, lag

    def __call__(self, t: np.ndarray, left=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Angle, rate and acceleration (rad, rad/s, rad/s^2) at the times ``t``."""
        angle, rate, acceleration = self.plan(t, left)
        return angle + self.lag.angle, rate, acceleration


class WinchCommand:
    """The commanded winch angle across a closed loop's samples.

    Parameters
    ----------
    settings : MpcSettings
        Resolved (the sample and the controller's step set).
    control : HermiteIntervals
        The controller's plan control.
    top : callable
        The true top motion ``t -> (position, velocity, acceleration)``, as the winch's own
        heave sensor measures it.
    radius : float, m
        Drum radius.
    forecast : TopForecast
        The top forecast at t = 0, the heave reference's start.

    Attributes
    ----------
    plan : Plan
        The plan in force (at rest until the first successful solve).
    """

    def __init__(
        self,
        settings: MpcSettings,
        control: HermiteIntervals,
        top,
        radius: float,
        forecast: TopForecast,
    ):
        self.settings, self.control, self.top, self.radius = settings, control, top, radius
        self.plan = Plan(0.0, np.zeros(control.size), control)
        self.previous = forecast
        self.height = BlendedHeight(forecast, forecast, 0.0, settings.sample)

    def winch(self, now: float, lag: Lag = ON_COMMAND) -> tuple[float, float]:
        """The planned angle and rate (rad, rad/s) at ``now`` (s): where a new plan starts.

        With the plant's drum ``lag`` behind the command (:mod:`.drum`), at the drum's angle:
        the controller plans from there, so that a saturated drum does not wind the plan up.
        The rate stays the plan's (the drum's may lie beyond the plan's bounds, the heave
        feedback's share added); its lag stays with the drum.
        """
        phi, rate, _ = self.plan(np.array([now]))
        return float(phi[0]) + lag.angle, float(rate[0])

    def angle(self, t, left=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Angle, rate and acceleration commanded at the times ``t`` (s)."""
        phi, rate, acc = self.plan(t, left)
        if not self.settings.heave_feedback:
            return phi, rate, acc
        position, velocity, acceleration = self.top(t)
        height, speed, height_acc = self.height(t)
        payout = heave_payout(
            position[2] - height, velocity[2] - speed, acceleration[2] - height_acc, self.radius
        )
        return phi + payout[0], rate + payout[1], acc + payout[2]

    def make_step(self, now: float, solve: Solve, estimate: Estimate, lag: Lag = ON_COMMAND):
        """The command from ``now`` (s) on, after the solve there: :meth:`angle`.

        A successful solve's plan takes over (blended in over one controller step) from the
        plan in force moved by the drum's angle ``lag`` (:meth:`.plant.Plant.take_lag`); a
        failed one leaves the plan in force. The heave reference blends to the estimate's
        forecast over the sample. ValueError, naming the argument, for a ``solve`` or an
        ``estimate`` of another kind (None, say) or a ``now`` before the plan in force.
        """
        for name, value, kind in (("solve", solve, Solve), ("estimate", estimate, Estimate)):
            if not isinstance(value, kind):
                raise ValueError(
                    f"{name} = {value!r:.60}: expected the {kind.__name__} that "
                    f"{'RecedingHorizon' if kind is Solve else 'Estimator'}.make_step returned"
                )
        number = isinstance(now, int | float | np.number) and not isinstance(now, bool)
        if not number or not np.isfinite(now) or now < self.plan.start:
            raise ValueError(
                f"now = {now!r} s: must be finite and not before the plan in force "
                f"(from t = {self.plan.start:g} s)"
            )
        if solve.success:
            previous = self.plan.settled()
            if not lag.on_track:
                previous = Shifted(previous, now, lag)
            self.plan = Plan(now, solve.parameters, self.control, previous, self.settings.step)
        if self.settings.heave_feedback:
            self.height = BlendedHeight(self.previous, estimate.forecast, now, self.settings.sample)
        self.previous = estimate.forecast
        return self.angle
