"""The reference descent of a lowering: the line out that lands the end, and a smooth way there.

A scene with ``[lowering]`` and ``[winch.line]`` asks for the end ``lowering.height`` above the
seabed at ``lowering.land_time``. :func:`landing_line` finds the line out whose hanging
equilibrium (the vessel where it is at the landing, the current on) puts the end there;
:func:`reference_descent` pays the line out to it along a rate plateau with C2 ramps (a planner's
profile, CONVENTIONS.md §5, lowering): the pay-out rate rises by a quintic smoothstep over ``t_r``,
holds ``v``, and falls back to zero by the same ramp at the landing, so that the pay-out's
acceleration is continuous and the end arrives at rest. The ramps are as long as the winch's
rate limit lets them be (``t_r = T/2``, a single S-curve, without one).
"""

from __future__ import annotations

from dataclasses import dataclass
from types import MappingProxyType

import numpy as np

from cable_ocp.drive.bounds import BOUND_TOLERANCE
from cable_ocp.drive.vessel import smoothstep
from cable_ocp.lowering.files import Flat
from cable_ocp.model.cable import spec_from_scene
from cable_ocp.model.line_models import line_models
from cable_ocp.simulation.line_run import SegmentDrive, pay_out_drive
from cable_ocp.simulation.seabed import clearance, clearance_reference
from cable_ocp.simulation.statics import starting_state

# The landing line is found when its static end is this close to the target height, m.
LANDING_LINE_TOLERANCE = 1e-4
LANDING_LINE_ITERATIONS = 20
# Share of the winch's rate and acceleration limits a reference descent may use: the closed
# loop's heave compensation and the optimiser's corrections need the rest.
LIMIT_SHARE = 0.8
SMOOTHSTEP_PEAK_SLOPE = 1.875  # largest slope of 10 s^3 - 15 s^4 + 6 s^5 on [0, 1]


class DescentError(ValueError):
    """A lowering that no descent within the winch's limits can fly; names the field to change."""


@dataclass(frozen=True)
class ReferenceDescent(Flat):
    """A pay-out from ``start_line`` to ``landing_line`` (m) over ``land_time`` (s), then held.

    Attributes
    ----------
    start_line, landing_line : float, m
        Line out at t = 0 and at the landing.
    land_time : float, s
    ramp : float, s
        Length ``t_r`` of each C2 ramp of the pay-out rate.
    drum_radius : float, m
    """

    # CF units of the fields kept as variables (result_files.units).
    UNITS = MappingProxyType({
        "start_line": "m", "landing_line": "m", "land_time": "s", "ramp": "s", "drum_radius": "m",
    })  # fmt: skip

    start_line: float
    landing_line: float
    land_time: float
    ramp: float
    drum_radius: float

    @property
    def cruise_rate(self) -> float:
        """The plateau's pay-out rate ``v = Delta L / (T - t_r)``, m/s."""
        return (self.landing_line - self.start_line) / (self.land_time - self.ramp)

    @property
    def peak_acceleration(self) -> float:
        """The largest pay-out acceleration, ``1.875 v / t_r``, m/s^2."""
        return SMOOTHSTEP_PEAK_SLOPE * abs(self.cruise_rate) / self.ramp

    def line_out(self, t) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Line out (m) with its rate (m/s) and acceleration (m/s^2) at times ``t`` (s)."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        T, ramp, v = self.land_time, self.ramp, self.cruise_rate
        rise, rise_slope, rise_area = smoothstep(np.clip(t / ramp, 0.0, 1.0))
        fall, fall_slope, fall_area = smoothstep(np.clip((T - t) / ramp, 0.0, 1.0))
        # The rate is v times the product of a rising and a falling ramp (each 1 where the
        # other works, since t_r <= T/2); the line out is its integral, in closed form (the
        # smoothstep's area over a whole ramp is 1/2).
        rate = v * rise * fall
        slope = v * (rise_slope / ramp * (t < ramp) * (t > 0))
        slope -= v * (fall_slope / ramp * (t > T - ramp) * (t < T))
        paid = v * (ramp * rise_area + np.clip(t - ramp, 0.0, T - 2 * ramp))
        paid += v * ramp * (0.5 - fall_area) * (t > T - ramp)
        return self.start_line + paid, rate, slope

    def angle(self, t, left=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The winch angle of the descent, ``(L(t) - L_0) / r_D``, with its rates (rad, /s, /s^2).

        C2 everywhere (``left`` is ignored): a winch angle history of
        :mod:`cable_ocp.drive.winch`.
        """
        line, rate, acceleration = self.line_out(t)
        r = self.drum_radius
        return (line - self.start_line) / r, rate / r, acceleration / r


def landing_end(scene, line_out: float, time: float | None = None) -> np.ndarray:
    """The end's hanging position (3,) with ``line_out`` (m) out, m.

    The static equilibrium of the line at that length under the vessel where the scene's top
    motion has it at ``time`` (s; default ``lowering.land_time``), in the scene's current.
    """
    time = scene.lowering.land_time if time is None else time
    mesh = scene.winch.line.mesh
    n = mesh.starting_elements(line_out)
    models = line_models(spec_from_scene(scene), mesh.element_length, compiled=True)
    paid = (line_out - scene.cable.length) / scene.winch.drum_radius

    def held(t, left=None):
        zeros = np.zeros(np.atleast_1d(t).shape)
        return zeros + paid, zeros, zeros.copy()

    drive = SegmentDrive(pay_out_drive(scene, held), time, scene.cable.length - mesh.below_top(n))
    return starting_state(models.model(n), drive, compiled=True)[:3]


def seabed_reference(scene) -> float:
    """The seabed's reference ``r`` of the scene's runs (m): from the hanging start at t = 0."""
    return clearance_reference(scene.seabed, landing_end(scene, scene.cable.length, 0.0))


def landing_line(scene) -> float:
    """The line out (m) whose hanging end is ``lowering.height`` above the seabed under it.

    Secant iterations from the vertical drop (each a static equilibrium, :func:`landing_end`),
    to :data:`LANDING_LINE_TOLERANCE`. The seabed's reference is the scene's own (its start).

    Raises
    ------
    DescentError
        The target is at or above the end's start (naming ``lowering.height``), the end starts
        under the seabed, or the landing line lies outside what the drum can pay out and haul in
        (:func:`line_range`).
    """
    lowering = scene.lowering
    reference = seabed_reference(scene)

    def miss(length: float) -> float:
        end = landing_end(scene, length)
        return float(clearance(scene.seabed, end, reference)) - lowering.height

    lengths = [scene.cable.length]
    misses = [miss(lengths[0])]
    _check_target(scene, lowering.height + misses[0])
    lengths.append(_within_drum(scene, lengths[0] + misses[0]))
    misses.append(miss(lengths[1]))
    for _ in range(LANDING_LINE_ITERATIONS):
        if abs(misses[-1]) < LANDING_LINE_TOLERANCE:
            return lengths[-1]
        slope = (misses[-1] - misses[-2]) / (lengths[-1] - lengths[-2])
        # The end falls by about what is paid out: a slope far from -1 is a poor secant.
        slope = slope if -2.0 < slope < -0.2 else -1.0
        lengths.append(_within_drum(scene, lengths[-1] - misses[-1] / slope))
        misses.append(miss(lengths[-1]))
    least, most = line_range(scene)
    raise DescentError(
        f"lowering.height = {lowering.height!r} m: no line out between {least:g} and {most:g} m "
        f"hangs the end there (last tried {lengths[-1]:.6g} m, {misses[-1]:+.3g} m off)"
    )


def line_range(scene) -> tuple[float, float]:
    """The least and the most line out (m) the drum of a ``[winch.line]`` scene can give.

    ``cable.length - winch.line.haul_in_max`` and ``cable.length + winch.line.pay_out_max``.
    """
    line = scene.winch.line
    return scene.cable.length - line.haul_in_max, scene.cable.length + line.pay_out_max


def _check_target(scene, start: float) -> None:
    """Refuse a lowering whose end starts at or under its target: ``start`` (m) above the seabed.

    A lowering pays out; a target above the start would be a haul-in, which the drum's
    ``haul_in_max`` is not the cause of (DescentError naming ``lowering.height`` and its range,
    or the seabed when the end starts under it).
    """
    height = scene.lowering.height
    if start <= 0:
        raise DescentError(
            f"seabed: the end starts {-start:.6g} m under the seabed (its hanging start with "
            f"cable.length = {scene.cable.length:g} m): nothing to lower onto; place the seabed "
            "below the start (seabed.clearance, or the grid) or shorten cable.length"
        )
    if height >= start:
        raise DescentError(
            f"lowering.height = {height!r} m is out of range: must be < {start:.6g} m, the end's "
            "height above the seabed at the start (a lowering pays the line out to its target)"
        )


def _within_drum(scene, length: float) -> float:
    """``length`` (m), or a DescentError naming the drum's metres when it cannot pay it out."""
    least, most = line_range(scene)
    if not least <= length <= most:
        field = "pay_out_max" if length > most else "haul_in_max"
        raise DescentError(
            f"winch.line.{field}: the landing needs about {length:.6g} m of line out, but the "
            f"drum holds {least:g} to {most:g} m (raise winch.line.{field}, or lowering.height)"
        )
    return length


def reference_descent(scene, landing: float | None = None) -> ReferenceDescent:
    """The planner's descent of a ``[lowering]`` scene: a rate plateau between C2 ramps.

    Parameters
    ----------
    scene : Scene
        With ``[lowering]`` and ``[winch.line]``.
    landing : float, optional, m
        The landing line out (default: :func:`landing_line`).

    Raises
    ------
    DescentError
        The landing time is too short for the winch's rate or acceleration limit (at
        :data:`LIMIT_SHARE` of each), naming ``lowering.land_time`` and the shortest that works.
    """
    if scene.winch.line is None or scene.lowering is None:
        raise ValueError("a reference descent needs a scene with [lowering] and [winch.line]")
    landing = landing_line(scene) if landing is None else landing
    T, r = scene.lowering.land_time, scene.winch.drum_radius
    distance = abs(landing - scene.cable.length)
    rate_limit = _limit(scene.winch.rate_max, r)
    ramp = T / 2 if rate_limit is None else min(T / 2, T - distance / rate_limit)
    shortest = 0.0 if rate_limit is None else distance / rate_limit
    if ramp <= BOUND_TOLERANCE * T:
        raise DescentError(
            f"lowering.land_time = {T!r} s is out of range: must be > {shortest:.6g} s (the "
            f"{distance:.6g} m to the landing at {LIMIT_SHARE:g} of winch.rate_max)"
        )
    descent = ReferenceDescent(scene.cable.length, landing, T, ramp, r)
    acceleration_limit = _limit(scene.winch.acceleration_max, r)
    if acceleration_limit is not None and descent.peak_acceleration > acceleration_limit:
        # The acceleration 1.875 D / (t_r (T - t_r)) is least at t_r = T/2; within both limits
        # T must reach the larger of the two shortest times.
        by_acceleration = np.sqrt(4 * SMOOTHSTEP_PEAK_SLOPE * distance / acceleration_limit)
        raise DescentError(
            f"lowering.land_time = {T!r} s is out of range: the descent's pay-out acceleration "
            f"{descent.peak_acceleration:.4g} m/s^2 exceeds {LIMIT_SHARE:g} of "
            f"winch.acceleration_max ({acceleration_limit:.4g} m/s^2 at the drum); lengthen it "
            f"(an S-curve of {by_acceleration:.6g} s keeps within it) or raise the limit"
        )
    return descent


def _limit(angular: float | None, radius: float) -> float | None:
    """A winch limit in rad/s or rad/s^2 as the line's m/s or m/s^2, at the usable share."""
    return None if angular is None else LIMIT_SHARE * angular * radius
