"""The plant: the scene's own model, driven by the true top motion and the winch angle applied.

The winch angle applied is the controller's plan (the commanded angle, for the top motion it
forecast) plus, with heave feedback, the pay-out ``(z_A - z_forecast) / r_D`` of the measured top
height's departure from the forecast (the compensation of eq. 38 on the measured motion, at the
plant's rate, as an active heave-compensated winch does). The applied angle is held inside the
winch's angle range (with the top-element length range) by a soft limiter (:meth:`Plant.apply`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from cable_ocp.control.closed_loop.projection import chain_state, plant_joints
from cable_ocp.drive.drive import Drive, end_force
from cable_ocp.drive.vessel import top_motion
from cable_ocp.model.cable import CableModel
from cable_ocp.model.layout import INPUTS
from cable_ocp.simulation.integrate import SimulationError, step_function
from cable_ocp.simulation.statics import equilibrium

# Relative offset (of the step) that places the end stage of an RK4 step just before the step end.
LEFT_LIMIT = 1e-6
# Width of the soft limiter at each end of the winch range (rad).
LIMITER_BAND = 0.2
AngleFunction = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray, np.ndarray]]


@dataclass(frozen=True)
class Applied:
    """Winch angle applied over some times, with its rates and where the limiter acted.

    Attributes
    ----------
    angle, rate, acceleration : arrays (k,), rad, rad/s, rad/s^2
    limited : array of bool (k,)
        The soft limiter changed the commanded angle.
    """

    angle: np.ndarray
    rate: np.ndarray
    acceleration: np.ndarray
    limited: np.ndarray


class Plant:
    """The scene's model integrated by RK4 at the scene's step, compiled to C.

    Parameters
    ----------
    scene : Scene
    angle_range : (float, float), rad
        The range the applied angle is held in.
    """

    def __init__(self, scene, angle_range: tuple[float, float]):
        self.scene = scene
        self.model = CableModel.from_scene(scene)
        self.step = scene.numerics.step
        self.top = top_motion(scene.top)
        self.radius = scene.winch.drum_radius
        self.segment = scene.segment_length
        self.low, self.high = angle_range
        self._step = step_function(self.model, self.step, compiled=True)
        self._runs: dict[int, object] = {}

    def apply(self, angle: AngleFunction, t: np.ndarray) -> Applied:
        """Limit a commanded angle history to the winch range at the times ``t``.

        Within :data:`LIMITER_BAND` of a bound the angle bends smoothly towards it (``b (1 -
        exp(-x / b))`` beyond the band's start ``x = 0``), so the applied angle never leaves the
        range and its rate stays continuous: a hard clip would jump the pay-out speed, which
        breaks the bonds (Baumgarte only restores them slowly).
        """
        phi, rate, acceleration = (np.array(v, dtype=float) for v in angle(t))
        limited = np.zeros(phi.shape, dtype=bool)
        band = LIMITER_BAND
        for sign, edge in ((1.0, self.high - band), (-1.0, self.low + band)):
            over = sign * (phi - edge)
            active = over > 0
            limited |= active
            decay = np.exp(-over[active] / band)
            slope, curvature = decay, -decay / band
            phi[active] = edge + sign * band * (1 - decay)
            acceleration[active] = (
                curvature * sign * rate[active] ** 2 + slope * acceleration[active]
            )
            rate[active] = slope * rate[active]
        return Applied(phi, rate, acceleration, limited)

    def inputs(self, applied: Applied, t: np.ndarray) -> np.ndarray:
        """Model inputs (15, len(t)) under the true top motion and the applied angle."""
        position, velocity, acceleration = self.top(t)
        length = np.vstack(
            [
                self.segment / 2 + self.radius * applied.angle,
                self.radius * applied.rate,
                self.radius * applied.acceleration,
            ]
        )
        return np.vstack([position, velocity, acceleration, length, end_force(self.scene.end, t)])

    def initial_state(self, applied: Applied) -> np.ndarray:
        """Static equilibrium at t = 0, set moving with the top and the winch (bonds held).

        The joints below the top are at rest; the top element turns with the top's velocity
        across it, so that the initial velocities satisfy the bonds even when the top (heave) or
        the winch is moving at t = 0.
        """
        model = self.model
        x = equilibrium(model, Drive.from_scene(self.scene), compiled=True).state
        u = self.inputs(applied, np.zeros(1))[:, 0]
        joints, _ = plant_joints(model, x)
        top, velocity = u[INPUTS.top], u[INPUTS.top_velocity]
        upper = np.vstack([joints[1:], top])
        directions = upper - joints
        rates = np.zeros_like(directions)
        rates[-1] = velocity / np.linalg.norm(directions[-1])
        length, length_rate = u[INPUTS.top_length], u[INPUTS.top_length_rate]
        return chain_state(model, top, velocity, length, length_rate, directions, rates)

    def advance(self, x: np.ndarray, start: float, count: int, angle: AngleFunction):
        """Integrate ``count`` steps from ``x`` at ``start`` (s) under a commanded angle.

        Returns
        -------
        states : array (count + 1, state_size)
            At ``start + k h``, ``k = 0..count``.
        inputs : array (count + 1, 15)
        applied : Applied
            At the same times.

        Raises
        ------
        SimulationError
            If the state becomes non-finite or leaves its bonds (numerics.constraint_tolerance).
        """
        h = self.step
        times = start + np.arange(count + 1) * h
        # The end stage of a step takes the input's left limit: the plan's acceleration jumps
        # at its nodes, which fall on step ends, and the right limit there cost 2e-3 m/s of
        # bond rate per node.
        stage_times = (times[:-1, None] + np.array([0.0, h / 2, h * (1 - LEFT_LIMIT)])).ravel()
        stage_applied = self.apply(angle, stage_times)
        stages = self.inputs(stage_applied, stage_times)
        if count not in self._runs:
            self._runs[count] = self._step.mapaccum(count)
        states = np.array(self._runs[count](x, stages)).T
        states = np.vstack([x, states])
        applied = self.apply(angle, times)
        inputs = self.inputs(applied, times).T
        self._check(states[-1], inputs[-1], times[-1])
        return states, inputs, applied

    def _check(self, x: np.ndarray, u: np.ndarray, t: float) -> None:
        if not np.all(np.isfinite(x)):
            raise SimulationError(
                f"the plant state became non-finite by t = {t:.6g} s (numerics.step = "
                f"{self.step} s): the RK4 step is beyond its stability limit"
            )
        residual = float(np.max(np.abs(self.model.output_values(x, u)["bond_residual"])))
        tolerance = self.scene.numerics.constraint_tolerance
        if residual > tolerance:
            raise SimulationError(
                f"the plant's bond residual {residual:.3g} m exceeds "
                f"numerics.constraint_tolerance = {tolerance:g} m at t = {t:.6g} s. Measured on "
                "paper_hill, this happens when the winch is driven into its bound with heave "
                "(mpc heave_margin < 1); keep heave_margin = 1 or reduce numerics.step"
            )
