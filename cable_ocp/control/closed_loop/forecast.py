"""The controller's forecast of the top motion: constant velocity from what was measured so far.

Horizontally the top goes on from its measured position at its measured velocity. Vertically it
goes on from the low-passed measured height at the low-passed vertical speed
(:class:`HeightFilter`): the wave motion (heave) is filtered out, so that the controller plans for
the vessel's mean motion and does not extrapolate a wave's momentary vertical speed over its whole
horizon; the heave about the filtered height is left to the heave feedback of the plant loop
(:mod:`.plant`). A straight line fitted to the heights of the last 20 s instead
passed on 0.25 m of an 8 s, 1 m heave to the end (Omega 0.23 m on paper_hill).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class TopForecast:
    """Top motion ``p(t) = position + velocity (t - start)`` over a horizon.

    Attributes
    ----------
    start : float, s
    position : array (3,), m
        Forecast top position at ``start``.
    velocity : array (3,), m/s
    """

    start: float
    position: np.ndarray
    velocity: np.ndarray

    def height(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Forecast top height and vertical speed at the times ``t`` (m, m/s)."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        return self.position[2] + self.velocity[2] * (t - self.start), np.full(
            t.size, self.velocity[2]
        )


class HeightFilter:
    """Critically damped second-order low-pass of the measured top height.

    ``y'' = w^2 (z - y) - 2 w y'`` with ``w = 1 / time_constant``: a wave of period ``P`` passes
    with the gain ``1 / (1 + (2 pi time_constant / P)^2)`` (1.1 % for 8 s waves and 15 s), a
    steady trend with no error. Integrated by semi-implicit Euler at the measurement step.

    Parameters
    ----------
    time_constant : float, s
    height : float, m
        The first measured height (the filter starts there, at rest).
    """

    def __init__(self, time_constant: float, height: float):
        self.rate_constant = 1.0 / time_constant
        self.height, self.speed = float(height), 0.0

    def update(self, step: float, heights: np.ndarray) -> np.ndarray:
        """Feed heights measured every ``step`` seconds; returns the filtered heights (m)."""
        w = self.rate_constant
        out = np.empty(len(heights))
        for k, z in enumerate(heights):
            self.speed += step * (w * w * (z - self.height) - 2 * w * self.speed)
            self.height += step * self.speed
            out[k] = self.height
        return out


def forecast_top(
    now: float, position: np.ndarray, velocity: np.ndarray, height: HeightFilter
) -> TopForecast:
    """Forecast the top from its measurement now.

    Parameters
    ----------
    now : float, s
    position, velocity : arrays (3,), m, m/s
        Measured top position and velocity now.
    height : HeightFilter
        The low-passed top height, which replaces the measured height and vertical speed.
    """
    position = np.array(position, dtype=float)
    speed = np.array(velocity, dtype=float)
    position[2], speed[2] = height.height, height.speed
    return TopForecast(start=float(now), position=position, velocity=speed)


@dataclass(frozen=True)
class BlendedHeight:
    """The top height the heave feedback measures against: from one forecast to the next.

    Over ``[start, start + span]`` the height passes from the previous forecast's line to the new
    one by the quintic smoothstep ``S``, so that it, its rate and its acceleration stay continuous
    when a new forecast arrives (a jump would make the winch jump the top-element length).

    Attributes
    ----------
    previous, current : TopForecast
    start, span : float, s
    """

    previous: TopForecast
    current: TopForecast
    start: float
    span: float

    def __call__(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Height, vertical speed and acceleration at the times ``t`` (m, m/s, m/s^2)."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        old, old_speed = self.previous.height(t)
        new, new_speed = self.current.height(t)
        tau = np.clip((t - self.start) / self.span, 0.0, 1.0)
        keep = 1 - tau**3 * (10 - 15 * tau + 6 * tau**2)
        keep_rate = -30 * tau**2 * (1 - tau) ** 2 / self.span
        keep_acc = -(60 * tau - 180 * tau**2 + 120 * tau**3) / self.span**2
        gap, gap_speed = old - new, old_speed - new_speed
        height = new + keep * gap
        speed = new_speed + keep * gap_speed + keep_rate * gap
        acceleration = 2 * keep_rate * gap_speed + keep_acc * gap
        return height, speed, acceleration
