"""The landing reference: the clearance error a fixed-``n`` landing asks the end to follow.

A scene of fixed ``n`` with a ``[lowering]`` table is a landing from a hover: the load hangs
where the line holds it at t = 0 and is to be brought down (or up) to ``lowering.height`` above
the seabed under it at ``lowering.land_time``, slowly, then held there (CONVENTIONS.md §5,
lowering). The objective of such a scene is the RMS of the end's deviation from the reference
height

    h_ref(t) = h_0 + (height - h_0) S(t / T_land),

``h_0`` the start's height above the seabed and S the quintic smoothstep (value, slope and
curvature 0 at both ends: the reference leaves the hover at rest and lands at zero speed, and is
held after T_land). In terms of the clearance error ``e = z_E - z_sb - delta`` (eq. 39), whose
reference this module gives, the end should follow

    e_ref(t) = h_ref(t) - delta = e_0 + (height - delta - e_0) S(t / T_land),

``e_0`` the start's error. Every score of such a run (its Trajectory's ``e(t)`` and Omega, the
winch problem's error) is ``e - e_ref``; every other scene has ``e_ref = 0`` and is unchanged.
A scene with ``[winch.line]`` lands by the lowering layer's descent instead
(:mod:`cable_ocp.lowering.plan`).
"""

from __future__ import annotations

import numpy as np

from cable_ocp.drive.vessel import smoothstep


def is_landing(scene) -> bool:
    """Whether the scene is a fixed-``n`` landing (``[lowering]`` without ``[winch.line]``)."""
    return scene.lowering is not None and scene.winch.line is None


def reference_error(scene, times, start_error: float) -> np.ndarray:
    """``e_ref(t)`` (m) of the module docstring at ``times`` (s); zeros for other scenes.

    Parameters
    ----------
    scene : Scene
    times : array, s
        From the scene's start.
    start_error : float, m
        ``e_0``: the clearance error of the end at t = 0.
    """
    times = np.asarray(times, dtype=float)
    if not is_landing(scene):
        return np.zeros(times.shape)
    lowering = scene.lowering
    drop = lowering.height - scene.seabed.clearance - start_error
    return start_error + drop * smoothstep(times / lowering.land_time)[0]
