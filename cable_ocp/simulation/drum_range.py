"""The drum's limits after a run: its angle, rate and acceleration within the winch's bounds.

``winch.angle_min`` and ``winch.angle_max`` bound the angle the drum can turn to (for a line on
the drum, ``-haul_in_max / r_D`` and ``pay_out_max / r_D``); ``winch.rate_max`` and
``winch.acceleration_max``, when set, bound ``|phi'|`` and ``|phi''|`` of the commanded profile
(heave compensation comes on top, as for the optimiser: :mod:`cable_ocp.drive.bounds`). A run
driven beyond them (a profile written by hand, an optimum replayed on a narrower winch) shows a
drum the scene does not have: it fails its physics check (:mod:`cable_ocp.simulation.slack`),
with the field, the value reached and the time (an acceleration beyond its bound is a note,
:func:`rate_findings`). A value outside by at most
:data:`~cable_ocp.drive.bounds.BOUND_TOLERANCE` counts as within, as for the optimiser's
solutions.
"""

from __future__ import annotations

import numpy as np

from cable_ocp.drive.bounds import BOUND_TOLERANCE
from cable_ocp.drive.drive import Drive
from cable_ocp.model.layout import INPUTS

CANNOT = ": the scene's drum cannot turn so"  # the end of a failure's line


def beyond(
    time: np.ndarray,
    values: np.ndarray,
    low: float,
    high: float,
    what: str,
    unit: str,
    fields: tuple[str, str],
    tolerance: float = BOUND_TOLERANCE,
) -> str | None:
    """The sample of ``values`` furthest outside ``[low, high]`` by more than ``tolerance``.

    ``fields`` names the lower and the upper bound's ``winch`` field; None when no sample is
    outside. The line reads ``the drum {what} {value} {unit} at t = ..., beyond winch.{field}``.
    """
    excess = np.maximum(low - values, values - high)
    outside = excess > tolerance
    if not outside.any():
        return None
    k = int(np.argmax(np.where(outside, excess, -np.inf)))
    field, bound = (fields[1], high) if values[k] > high else (fields[0], low)
    return (
        f"the drum {what} {values[k]:.4g} {unit} at t = {time[k]:g} s, beyond winch.{field} = "
        f"{bound:g} {unit} (outside from t = {time[int(np.argmax(outside))]:g} s, "
        f"{np.count_nonzero(outside)} of {time.size} samples)"
    )


def drum_failure(winch, time: np.ndarray, angle: np.ndarray) -> str | None:
    """Where a run's drum went furthest beyond its angle range, or None if it never did.

    Parameters
    ----------
    winch : Winch
        The scene's winch (``angle_min``, ``angle_max``, rad).
    time : array (k,), s
    angle : array (k,), rad
        The drum angle at ``time``, heave compensation included.

    Returns
    -------
    str or None
        ``the drum turned to 35.2 rad at t = 12 s, beyond winch.angle_max = 24 rad`` for the
        sample furthest outside, with how long the drum stayed outside.
    """
    angle = np.asarray(angle, dtype=float)
    found = beyond(
        time, angle, winch.angle_min, winch.angle_max, "turned to", "rad",
        ("angle_min", "angle_max"),
    )  # fmt: skip
    return found and f"{found}{CANNOT}"


def profile_rates(scene, time: np.ndarray, inputs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The commanded profile's ``phi'`` (rad/s) and ``phi''`` (rad/s^2) at a run's samples.

    The drive's top-length rates (``inputs``, (k, 15)) over ``winch.drum_radius``, less the heave
    compensation's part when the scene has one.
    """
    radius = scene.winch.drum_radius
    rate = inputs[:, INPUTS.top_length_rate] / radius
    acceleration = inputs[:, INPUTS.top_length_acceleration] / radius
    if scene.top.heave_compensated:
        _, heave_rate, heave_acceleration = Drive.from_scene(scene).winch_angle(time)
        rate, acceleration = rate - heave_rate, acceleration - heave_acceleration
    return rate, acceleration


def rate_findings(scene, time: np.ndarray, inputs: np.ndarray) -> tuple[str | None, str | None]:
    """Where a run's drum turned faster, or accelerated harder, than its winch allows.

    A rate beyond ``winch.rate_max`` fails the run. An acceleration beyond
    ``winch.acceleration_max`` is a note: an optimum paying a heave out as a feedforward and
    replayed on its scene (the heave then part of the profile) legitimately exceeds it (the
    bundled deep_lift's by 1.65 against 1.5 rad/s^2 for 0.2 s), since the optimiser bounds the
    profile's acceleration with the heave on top.

    Parameters
    ----------
    scene : Scene
        ``winch.rate_max`` (rad/s) and ``winch.acceleration_max`` (rad/s^2); None: unbounded.
    time : array (k,), s
    inputs : array (k, 15)
        The run's inputs (``INPUT_NAMES``) at ``time``.

    Returns
    -------
    rate_failure, acceleration_note : str or None
        ``the drum turned at 0.31 rad/s at t = 4 s, beyond winch.rate_max = 0.2 rad/s ...``,
        and the same for the acceleration; None where the run kept within the bound.
    """
    winch = scene.winch
    rate, acceleration = profile_rates(scene, time, inputs)
    found = [
        None if bound is None else beyond(time, values, -bound, bound, what, unit, (field, field))
        for values, bound, what, unit, field in (
            (rate, winch.rate_max, "turned at", "rad/s", "rate_max"),
            (acceleration, winch.acceleration_max, "accelerated at", "rad/s^2",
             "acceleration_max"),
        )
    ]  # fmt: skip
    rate_failure = found[0] and f"{found[0]}{CANNOT}"
    return rate_failure, found[1] and f"{found[1]} (a note: the heave may be on top of it)"
