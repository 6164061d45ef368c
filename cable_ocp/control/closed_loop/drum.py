"""The plant's drum: it follows the commanded winch angle within its rate and acceleration limits.

A physical drum saturates: the closed loop's command (the plan plus the heave feedback) may ask
for more rate or acceleration than the winch has (``winch.rate_max``, ``winch.acceleration_max``;
times ``r_D`` for the line). The drum's angle is the command's plus a **lag** ``d(t)``, zero while
the command is within the limits, so that a run that never saturates is the command's bit for
bit. Where the command asks for more, the drum's acceleration is clipped:

- to ``+-acceleration_max``;
- towards ``+-rate_max`` by a ramp over the last :data:`RATE_BAND` of the rate limit
  (``a <= k (rate_max - rate)``), so that the rate approaches its limit without a jump in the
  acceleration (a jump inside an RK4 step opens the bonds, :mod:`.plant`); a drum started
  beyond its rate limit (a command moving at t = 0) comes back to it at the acceleration limit;

and the lag is steered back to zero by a critically damped servo of bandwidth
:data:`DRUM_BANDWIDTH` (``d'' = -w^2 d - 2 w d'`` where nothing clips), itself clipped. The drum
is integrated on a grid of :data:`GRID_PER_STAGE` points per half RK4 step, its acceleration held
over each grid interval, so that its angle, rate and acceleration are exactly consistent at the
RK4 stages (which lie on the grid) and its limits hold exactly.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

# rad/s: the drum's servo brings a lag back within about a second (a wave period is 6-12 s).
DRUM_BANDWIDTH = 2.0
# Share of the rate limit over which the acceleration towards it is ramped down: at 20 % the
# approach takes a few tenths of a second (2 % made it a few hundredths, which RK4 at the plant's
# step did not resolve: the bonds opened by 1e-3 m).
RATE_BAND = 0.2
# Grid points of the lag's integration per half RK4 step (the stages lie on the grid).
GRID_PER_STAGE = 4
# A lag below this (rad, and rad/s over the bandwidth) is dropped at a sample's start: the drum is
# back on the command (a step of 1e-9 m of line, far inside any bond tolerance).
ON_TRACK = 1e-9


@dataclass(frozen=True)
class Lag:
    """The drum's angle less the command's, and its rate (rad, rad/s)."""

    angle: float = 0.0
    rate: float = 0.0

    @property
    def on_track(self) -> bool:
        """Whether the drum is (back) on the command."""
        return abs(self.angle) <= ON_TRACK and abs(self.rate) <= ON_TRACK * DRUM_BANDWIDTH


ON_COMMAND = Lag()  # the drum on the command


@dataclass(frozen=True)
class Drum:
    """The limits of a scene's winch, rad/s and rad/s^2 (``inf`` where it sets none)."""

    rate_max: float
    acceleration_max: float

    @classmethod
    def of(cls, winch) -> Drum:
        """The drum of a scene's ``[winch]``."""
        return cls(
            np.inf if winch.rate_max is None else float(winch.rate_max),
            np.inf if winch.acceleration_max is None else float(winch.acceleration_max),
        )

    @property
    def limited(self) -> bool:
        """Whether the winch sets any limit."""
        return bool(np.isfinite(self.rate_max) or np.isfinite(self.acceleration_max))

    def within(self, rate: np.ndarray, acceleration: np.ndarray) -> bool:
        """Whether a command's rates and accelerations (rad/s, rad/s^2) keep inside the limits."""
        return bool(
            np.all(np.abs(rate) <= self.rate_max)
            and np.all(np.abs(acceleration) <= self.acceleration_max)
        )

    def start(self, applied):
        """The drum at a run's start under a command ``applied`` there, and its lag.

        At the command's angle, its rate and acceleration clipped to the limits (a heave feedback
        can ask for more at t = 0); the lag's rate is the rate clipped off.
        """
        rate = np.clip(applied.rate, -self.rate_max, self.rate_max)
        acceleration = np.clip(applied.acceleration, -self.acceleration_max, self.acceleration_max)
        lag = Lag(0.0, float(rate[0] - applied.rate[0]))
        return replace(applied, rate=rate, acceleration=acceleration), lag

    def follow(self, lag: Lag, spacing: float, angle, rate, acceleration):
        """The drum on a uniform grid under a command, from ``lag`` at the grid's first point.

        The drum's acceleration is held over each grid interval, at the command's plus the
        servo's pull on the lag, clipped; its angle and rate are that acceleration's integrals,
        so that they are exactly consistent at the grid's points, and the limits hold exactly.

        Parameters
        ----------
        lag : Lag
            At the first point.
        spacing : float, s
            Of the grid.
        angle, rate, acceleration : arrays (g,), rad, rad/s, rad/s^2
            The command at the grid's points (the acceleration's right limit).

        Returns
        -------
        angle, rate, acceleration, acceleration_left : arrays (g,)
            The drum's; its acceleration over the interval that starts at each point, and over
            the one that ends there.
        saturated : array of bool (g,)
            The acceleration was clipped over the interval that starts there.
        lag : Lag
            At the grid's last point.
        """
        stiffness, damping = DRUM_BANDWIDTH**2, 2 * DRUM_BANDWIDTH
        a_max, w_max = self.acceleration_max, self.rate_max
        ramp = min(a_max / (RATE_BAND * w_max), 1 / spacing) if np.isfinite(w_max) else 0.0
        count = angle.size
        drum_angle, drum_rate = np.empty(count), np.empty(count)
        drum_acceleration = np.empty(count)
        saturated = np.zeros(count, dtype=bool)
        phi, omega = angle[0] + lag.angle, rate[0] + lag.rate
        for j in range(count):
            drum_angle[j], drum_rate[j] = phi, omega
            wanted = acceleration[j] - stiffness * (phi - angle[j]) - damping * (omega - rate[j])
            upper, lower = a_max, -a_max
            if ramp:  # beyond the rate limit (a start there), back at the acceleration limit
                upper = min(upper, max(ramp * (w_max - omega), -a_max))
                lower = max(lower, min(-ramp * (w_max + omega), a_max))
            applied = min(max(wanted, lower), upper)
            saturated[j] = applied != wanted
            drum_acceleration[j] = applied
            phi += omega * spacing + applied * spacing**2 / 2
            omega += applied * spacing
        left = np.concatenate([drum_acceleration[:1], drum_acceleration[:-1]])
        end = Lag(float(drum_angle[-1] - angle[-1]), float(drum_rate[-1] - rate[-1]))
        return drum_angle, drum_rate, drum_acceleration, left, saturated, end


def saturation_note(time: np.ndarray, saturated: np.ndarray, step: float) -> str:
    """When and how long a plant's drum saturated (empty if never).

    Parameters
    ----------
    time : array (k,), s
        The plant's steps.
    saturated : array of bool (k,)
        Whether the drum saturated in the step that ends at each time.
    step : float, s
        The plant's step.
    """
    k = np.flatnonzero(saturated)
    if not k.size:
        return ""
    breaks = np.flatnonzero(np.diff(k) > 1)
    starts, stops = k[np.r_[0, breaks + 1]], k[np.r_[breaks, k.size - 1]]
    lengths = (stops - starts + 1) * step
    longest = int(np.argmax(lengths))
    return (
        f"the drum saturated at its rate or acceleration limit for {k.size * step:.4g} s "
        f"({k.size} plant steps, {starts.size} spans) from t = {time[k[0]] - step:g} s, the "
        f"longest {lengths[longest]:.4g} s from t = {time[starts[longest]] - step:g} s"
    )
