"""Inputs of the model over time: top motion, top-element length (winch) and end force.

:class:`Drive` turns a scene and a winch-angle history into the input vector ``u(t)`` of
:data:`cable_ocp.model.cable.INPUT_NAMES`, vectorised over time.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cable_ocp.drive import winch
from cable_ocp.drive.vessel import TopMotionFunction, smoothstep, top_motion


def end_force(end, t: np.ndarray) -> np.ndarray:
    """External force at the free end (3, len(t)), N.

    ``F = force + amplitude * S((t - t0) / T_r) * (sin(2 pi (t - t0) / P) or 1 where P = 0)``
    (CONVENTIONS.md §6, the end_force scene).
    """
    t = np.atleast_1d(np.asarray(t, dtype=float))
    since = t - end.force_start
    ramp = smoothstep(since / end.force_ramp)[0] if end.force_ramp > 0 else (since >= 0) * 1.0
    force = np.tile(np.reshape(end.force, (3, 1)), (1, t.size))
    for k in range(3):
        period = end.force_period[k]
        wave = np.sin(2 * np.pi * since / period) if period > 0 else 1.0
        force[k] += end.force_amplitude[k] * ramp * wave
    return force


@dataclass(frozen=True)
class Drive:
    """Everything prescribed over time for one run.

    Attributes
    ----------
    top : callable
        Top motion ``t -> (position, velocity, acceleration)``.
    angle : callable
        Winch angle ``t -> (phi, phi', phi'')`` (rad), before heave compensation.
    end : EndLoad
        The scene's ``[end]`` section.
    top_length : float, m
        The top element at ``phi = 0`` (the model's mesh, ``Scene.mesh``).
    drum_radius : float, m
    heave_compensation : bool
        Add ``z_A / r_D`` to the winch angle (eq. 38).
    """

    top: TopMotionFunction
    angle: winch.WinchAngleFunction
    end: object
    top_length: float
    drum_radius: float
    heave_compensation: bool = False

    def __post_init__(self) -> None:
        winch.check_angle(self.angle)

    @classmethod
    def from_scene(
        cls, scene, angle: winch.WinchAngleFunction | None = None, elements: int | None = None
    ) -> Drive:
        """Drive of a scene; ``angle`` defaults to the locked winch."""
        n = elements or scene.model.elements
        return cls(
            top=top_motion(scene.top),
            angle=winch.with_left(angle or winch.locked),
            end=scene.end,
            top_length=scene.mesh(n)[1],
            drum_radius=scene.winch.drum_radius,
            heave_compensation=scene.top.heave_compensated,
        )

    def winch_angle(self, t: np.ndarray, left=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Winch angle with its rates (rad, rad/s, rad/s^2), heave compensation included.

        ``left`` (bool array like ``t``): left limits there (see :func:`stage_times`).
        """
        motion = self.top(t) if self.heave_compensation else None
        return self._paid_out(self.angle(t, left), motion)

    def _paid_out(self, angle: tuple, motion: tuple | None) -> tuple:
        """The winch angle with its rates, plus the heave compensation's payout.

        ``motion``: the top's position, velocity and acceleration at the angle's times (None:
        no compensation).
        """
        phi, rate, acc = angle
        if motion is not None:
            position, velocity, acceleration = motion
            start = self.top(np.zeros(1))[0][2]
            payout = winch.heave_payout(
                position[2] - start, velocity[2], acceleration[2], self.drum_radius
            )
            phi, rate, acc = phi + payout[0], rate + payout[1], acc + payout[2]
        return phi, rate, acc

    def inputs(self, t: np.ndarray, left=None) -> np.ndarray:
        """Input vector ``u`` at the times ``t`` (s): array (15, len(t)), see ``INPUT_NAMES``.

        ``left`` (bool array like ``t``): the winch's left limits there (see :func:`stage_times`).
        The top's motion is evaluated once for both (a sea state's components made half of a
        heave-compensated full-model run's time, evaluated twice).
        """
        t = np.atleast_1d(np.asarray(t, dtype=float))
        motion = self.top(t)
        angle = self._paid_out(self.angle(t, left), motion if self.heave_compensation else None)
        length = winch.top_length(angle, self.top_length, self.drum_radius)
        return np.vstack([*motion, length, end_force(self.end, t)])

    def stage_inputs(self, starts: np.ndarray, step: float) -> np.ndarray:
        """Inputs at the RK4 stages of the steps starting at ``starts``: array (15, 3 len)."""
        times, left = stage_times(starts, step)
        return self.inputs(times, left)


def stage_times(starts: np.ndarray, step: float) -> tuple[np.ndarray, np.ndarray]:
    """The RK4 stage times ``t, t + h/2, t + h`` of steps starting at ``starts`` (s), flattened.

    Returns
    -------
    times : array (3 len(starts),), s
    left : array of bool, like ``times``
        True at the end stages ``t + h``: a step that ends on a breakpoint of a piecewise input
        (the Hermite winch's acceleration jumps at its nodes) integrates its own piece, so its end
        stage takes the limit from the left.
    """
    starts = np.asarray(starts, dtype=float).ravel()
    times = (starts[:, None] + np.array([0.0, step / 2, step])[None, :]).ravel()
    left = np.tile(np.array([False, False, True]), starts.size)
    return times, left
