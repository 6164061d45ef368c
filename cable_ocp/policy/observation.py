"""What the policy sees: the measurements a winch controller has on board, as one vector.

At a sample of the closed loop (:func:`observe`), from the plant's :class:`Measurement` (what its
sensors give at the sample's end) and the controller's :class:`Estimate`:

- the drum's angle and rate (the winch's encoder: the plan's, as the controller starts from);
- the vessel's heave and heave rate (an MRU: the top's measured height and vertical speed);
- the line tension at the top (a load cell);
- the load's height above the seabed less its setpoint (an altimeter; the setpoint is the
  controller's own: the start's clearance, or a landing's reference at that time);
- the seabed ahead of the load along the vessel's track, at :data:`LOOK_AHEAD` distances, less
  the seabed under it (the bathymetry chart along the track that the vessel follows);
- the tow speed (the vessel's speed over ground).

Nothing else: no state of the rfe model, no forecast the real system cannot make. A point ahead
that falls off a bathymetry grid gives NaN, which the safety net reads as outside the training
envelope (:mod:`.safety`).
"""

from __future__ import annotations

import numpy as np

from cable_ocp.model.layout import INPUTS
from cable_ocp.simulation.landing_reference import reference_error
from cable_ocp.simulation.seabed import OffGridError, seabed_height
from cable_ocp.simulation.statics import bond_tensions

# m: how far ahead of the load, along the track, the policy sees the seabed.
LOOK_AHEAD = (5.0, 15.0, 30.0)
# m/s: below this tow speed the track has no direction; the seabed ahead is read along +x.
STILL = 1e-3

FEATURES = (
    "drum_angle", "drum_rate", "heave", "heave_rate", "tension", "clearance_error",
    *(f"seabed_ahead_{d:g}m" for d in LOOK_AHEAD), "tow_speed",
)  # fmt: skip
UNITS = (
    "rad", "rad/s", "m", "m/s", "N", "m", *("m" for _ in LOOK_AHEAD), "m/s",
)  # fmt: skip


def observe(scene, plant_model, measured, estimate, angle: float, rate: float) -> np.ndarray:
    """The observation at the end of a sample (:data:`FEATURES`, in :data:`UNITS`).

    Parameters
    ----------
    scene : Scene
        The plant's scene: its seabed (the chart and the setpoint's kind).
    plant_model : CableModel
        The plant's model, for the top tension at the measured state (the load cell).
    measured : Measurement
        What the plant measured over the sample (its last state and inputs hold at its end).
    estimate : Estimate
        The controller's estimate at the sample: the clearance reference and start error.
    angle, rate : float, rad, rad/s
        The drum's angle and rate, as the controller starts from them.
    """
    x, u = measured.states[-1], measured.inputs[-1]
    top_velocity = u[INPUTS.top_velocity]
    speed = float(np.hypot(top_velocity[0], top_velocity[1]))
    track = top_velocity[:2] / speed if speed > STILL else np.array([1.0, 0.0])
    end = x[:3]
    seabed = scene.seabed
    try:
        under = float(seabed_height(seabed, end[0], end[1]))
    except OffGridError:
        under = float("nan")
    ahead = []
    for distance in LOOK_AHEAD:
        point = end[:2] + distance * track
        try:
            ahead.append(float(seabed_height(seabed, point[0], point[1])) - under)
        except OffGridError:
            ahead.append(float("nan"))
    setpoint = float(reference_error(scene, np.array([measured.now]), estimate.start_error)[0])
    error = float(end[2]) - under - estimate.reference - setpoint
    tension = float(bond_tensions(plant_model, x, u)[-1])
    return np.array([angle, rate, u[INPUTS.top][2], top_velocity[2], tension, error, *ahead, speed])
