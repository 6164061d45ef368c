"""The estimator: what the controller knows at a sample, from the plant's measurements.

It low-passes the measured top height (:class:`.forecast.HeightFilter`), forecasts the top
(:func:`.forecast.forecast_top`), projects the plant's state onto the controller's model
(:mod:`.projection`) and keeps the room the heave feedback needs from the angle bounds: the
largest departure of the measured height from the filtered one over the last two filter time
constants, in rad of winch, plus the soft limiter's band.
"""

from __future__ import annotations

import numpy as np

from cable_ocp.control.closed_loop.controller import Estimate
from cable_ocp.control.closed_loop.forecast import HeightFilter, TopForecast, forecast_top
from cable_ocp.control.closed_loop.plant import Measurement
from cable_ocp.control.closed_loop.projection import project_state
from cable_ocp.control.closed_loop.settings import MpcSettings
from cable_ocp.model.cable import CableModel
from cable_ocp.model.layout import INPUTS


class Estimator:
    """Measurements in, :class:`.controller.Estimate` out.

    Parameters
    ----------
    settings : MpcSettings
    plant, reduced : CableModel
        The plant's model and the controller's.
    radius : float, m
        Drum radius.
    height : float, m
        The top height measured at t = 0 (the filter starts there, at rest).

    Attributes
    ----------
    reference : float, m
        Clearance reference of the plant's start (set once the plant has started).
    start_error : float, m
        The clearance error of the plant's start, ``e_0`` of a landing's reference
        (:mod:`~cable_ocp.simulation.landing_reference`; set with ``reference``).
    """

    def __init__(
        self,
        settings: MpcSettings,
        plant: CableModel,
        reduced: CableModel,
        radius: float,
        height: float,
    ):
        self.settings, self.plant, self.reduced, self.radius = settings, plant, reduced, radius
        self.reference = self.start_error = float("nan")
        self.filter = HeightFilter(settings.heave_filter, height)
        self.times = [np.zeros(1)]
        self.heights = [np.array([height], dtype=float)]
        self.filtered = [self.heights[0].copy()]

    def forecast(self, now: float, position: np.ndarray, velocity: np.ndarray) -> TopForecast:
        """The top forecast from its position and velocity measured at ``now`` (m, m/s)."""
        return forecast_top(now, position, velocity, self.filter)

    def measure(self, times: np.ndarray, inputs: np.ndarray, step: float) -> None:
        """Take the plant's inputs (k, 15) at the times (k,) of one sample, ``step`` apart."""
        self.times.append(times)
        self.heights.append(inputs[:, INPUTS.top][:, 2])
        self.filtered.append(self.filter.update(step, inputs[:, INPUTS.top][:, 2]))

    def filtered_heights(self) -> np.ndarray:
        """The low-passed top height at every measured time (m)."""
        return np.concatenate(self.filtered)

    def make_step(self, measured: Measurement, angle: float, rate: float) -> Estimate:
        """The estimate at the end of a sample from what the plant measured over it.

        The top heights measured since the last call go through the filter; the state and
        inputs at the sample's end make the estimate. ``angle``, ``rate`` (rad, rad/s): the
        plan's winch then, which sets the reduced model's top element. ValueError, naming the
        argument, for a ``measured`` that is no :class:`~.plant.Measurement` or an angle or
        rate that is not a finite number.
        """
        if not isinstance(measured, Measurement):
            raise ValueError(
                f"measured = {measured!r:.60}: expected the Measurement that Plant.start or "
                "Plant.make_step returned"
            )
        for name, value in (("angle", angle), ("rate", rate)):
            if isinstance(value, bool) or not np.isfinite(np.asarray(value, dtype=float)).all():
                raise ValueError(f"{name} = {value!r:.40}: expected a finite number (rad, rad/s)")
        new = measured.time > self.times[-1][-1]
        if np.any(new):
            self.measure(measured.time[new], measured.inputs[new], measured.step)
        return self.estimate(measured.now, measured.states[-1], measured.inputs[-1], angle, rate)

    def estimate(
        self, now: float, x: np.ndarray, u: np.ndarray, angle: float, rate: float
    ) -> Estimate:
        """The estimate at ``now`` (s) from the plant's state ``x`` and inputs ``u``."""
        forecast = self.forecast(now, u[INPUTS.top], u[INPUTS.top_velocity])
        projected = project_state(
            self.plant,
            x,
            u[INPUTS.top_length],
            self.reduced,
            forecast.position,
            forecast.velocity,
            self.reduced.spec.top_length + self.radius * angle,
            self.radius * rate,
        )
        margin = self.settings.limiter_band
        if self.settings.heave_feedback:
            times = np.concatenate(self.times)
            recent = times >= now - 2 * self.settings.heave_filter
            heights = np.concatenate(self.heights)[recent]
            departure = np.max(np.abs(heights - self.filtered_heights()[recent]))
            margin += self.settings.heave_margin * departure / self.radius
        return Estimate(
            projected.state, forecast, projected.end_offset, self.reference, float(margin),
            self.start_error,
        )  # fmt: skip
