"""The policy's action and the controller's plan: a drum rate over the next sample, both ways.

The action is the mean drum rate over the next sample, ``(phi(t + T_s) - phi(t)) / T_s``
(rad/s). :func:`label` reads it off a receding-horizon plan (the MPC's answer, the training
label); :func:`ramp` turns an action into a plan of the controller's own form (a free-start
Hermite angle, :class:`~cable_ocp.drive.controls.HermiteIntervals`), so that the closed loop's
command, its blending and its heave feedback run a policy's action as they run a solve: the plan
starts at the drum's angle and rate, reaches ``phi(t) + a T_s`` at the next sample, and holds a
constant rate at its later nodes.
"""

from __future__ import annotations

import numpy as np

from cable_ocp.drive.controls import HermiteIntervals


def label(control: HermiteIntervals, parameters: np.ndarray, sample: float) -> float:
    """The mean drum rate (rad/s) over the first ``sample`` seconds of a plan."""
    angle = control.evaluate(parameters, np.array([0.0, sample]))[0]
    return float(angle[1] - angle[0]) / sample


def ramp(
    control: HermiteIntervals, angle: float, rate: float, action: float, sample: float
) -> np.ndarray:
    """The plan of the action ``a`` (rad/s) from the drum's ``angle`` and ``rate`` (rad, rad/s).

    Node 0 holds the drum's angle and rate; nodes ``k >= 1`` lie on ``angle + c t_k`` with rate
    ``c``, the ``c`` for which the plan is at ``angle + a sample`` at ``sample`` (s, at most
    one interval: the closed loop's interval is a multiple of its sample).
    """
    times = control.breakpoints
    fixed = np.zeros(control.size)
    moving = np.zeros(control.size)
    for node, t in enumerate(times):
        at_angle, at_rate = control.node_indices(node)
        if node == 0:
            fixed[at_angle], fixed[at_rate] = angle, rate
        else:
            fixed[at_angle] = angle
            moving[at_angle], moving[at_rate] = t, 1.0
    basis = control.basis(np.array([sample]))[0][0]
    speed = (angle + action * sample - basis @ fixed) / (basis @ moving)
    return fixed + speed * moving
