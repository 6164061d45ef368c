"""The closed loop's settings, one dataclass built alike by the API and the CLI, checked once."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

REFERENCES = ("locked", "open-loop")
SOLVERS = ("gauss-newton", "ipopt")


def _multiple(value: float, unit: float) -> bool:
    """Whether ``value`` is a whole multiple of ``unit`` (to round-off)."""
    count = round(value / unit)
    return count >= 1 and abs(count * unit - value) <= 1e-9 * max(abs(value), 1.0)


@dataclass(frozen=True)
class MpcSettings:
    """How the receding-horizon controller is built and run.

    Attributes
    ----------
    horizon : float, s
        Prediction horizon; a multiple of ``sample``, at most the scene's duration.
    sample : float, s
        Time between solves; a multiple of the plant's step and of ``step``.
    interval : float, s
        Length of one interval of the plan (its Hermite nodes are this far apart); divides
        ``horizon``. Plans of 1 s intervals, re-solved every second, have the freedom to exploit
        the reduced model's errors: on the README's heave case Omega was 0.168 m with 1 s
        intervals against 0.046 m with 5 s ones (a 1 s sample, h = 1 s, converged solves).
    elements : int
        Elements of the controller's model.
    step : float, s
        Its RK4 step.
    solver : str
        ``"gauss-newton"``: one Gauss-Newton step per sample from the shifted previous plan (a
        real-time iteration: one simulation with sensitivities and one QP); ``"ipopt"``: IPOPT
        with a limited-memory Hessian on the multiple-shooting NLP, to convergence or
        ``max_iter``.
    heave_feedback : bool
        Add the measured top height's departure from the forecast to the plan (eq. 38 on the
        measured motion, :mod:`.plant`).
    heave_filter : float, s
        Time constant of the low-pass of the measured top height that makes the vertical forecast
        (:class:`cable_ocp.control.closed_loop.forecast.HeightFilter`).
    heave_margin : float
        Fraction of the measured heave (its largest departure from the filtered height over the
        last ``2 heave_filter`` seconds, in rad of winch) by which the plan keeps clear of the
        angle bounds, so that the heave feedback has room (0: none, 1: all of it). Room costs
        reach where the hill asks for it: on the README's heave case (1 s sample, the limiter's
        0.5 rad band) Omega was 0.0236 m at 0.5, 0.0473 m at 0.75; with a 0.2 rad band 0.0222 m
        at 0.5, 0.0619 m at 1, but the harder bend opened the plant's bonds on heaving
        robustness scenes (``limiter_band``).
    limiter_band : float, rad
        Width of the plant's soft limiter at each end of the winch range (the plan keeps clear
        of it too). Its bend accelerates the winch by about ``rate^2 / band``: at 0.2 rad (the
        earlier value) the heave feedback bent into a bound opened the plant's bonds by 1.4e-4
        to 3.6e-4 m on 5 of 35 heaving robustness scenes (seeds 0 and 3, 1 s sample); at 0.5
        rad on 1.
    rate_weight : float, s^2
        Weight of the pay-out speed ``(r_D phi')^2`` against ``e^2`` in the objective.
    max_iter : int
        Iterations per solve: IPOPT's, or Gauss-Newton steps (1: the real-time iteration).
    references : tuple of str
        Reference runs on the same plant: ``"locked"`` (winch locked), ``"open-loop"`` (the
        open-loop optimum of ``cable_ocp.optimize`` on the scene without its heave, applied as it
        is and with the heave feedback).
    """

    horizon: float = 20.0
    sample: float = 1.0
    interval: float = 5.0
    elements: int = 2
    step: float = 1.0
    solver: str = "gauss-newton"
    heave_feedback: bool = True
    heave_filter: float = 15.0
    heave_margin: float = 0.5
    limiter_band: float = 0.5
    rate_weight: float = 1e-4
    max_iter: int = 1
    references: tuple[str, ...] = ("locked",)

    def __post_init__(self):
        sample, horizon, step = self.sample, self.horizon, self.step
        if not (sample > 0 and math.isfinite(sample)):
            raise ValueError(f"sample = {sample} s: must be > 0")
        if not (horizon > sample and math.isfinite(horizon)):
            raise ValueError(f"horizon = {horizon} s: must be > sample = {sample} s")
        if not _multiple(horizon, sample):
            raise ValueError(
                f"horizon = {horizon} s must be a whole multiple of sample = {sample} s"
            )
        if not (isinstance(self.elements, int) and self.elements >= 1):
            raise ValueError(f"elements = {self.elements}: the controller's model needs >= 1")
        if not (step > 0 and _multiple(sample, step)):
            raise ValueError(f"step = {step} s: must be > 0 and divide sample = {sample} s")
        if not (self.interval > 0 and _multiple(horizon, self.interval)):
            raise ValueError(
                f"interval = {self.interval} s: must be > 0 and divide horizon = {horizon} s"
            )
        if not _multiple(self.interval, step):
            raise ValueError(f"step = {step} s: must divide interval = {self.interval} s")
        if self.solver not in SOLVERS:
            raise ValueError(f"solver = {self.solver!r}: must be one of {', '.join(SOLVERS)}")
        if not (self.heave_filter > 0 and math.isfinite(self.heave_filter)):
            raise ValueError(f"heave_filter = {self.heave_filter} s: must be > 0 (a time constant)")
        if not (isinstance(self.max_iter, int) and self.max_iter >= 1):
            raise ValueError(f"max_iter = {self.max_iter}: must be an integer >= 1")
        if not (self.limiter_band > 0 and math.isfinite(self.limiter_band)):
            raise ValueError(f"limiter_band = {self.limiter_band} rad: must be > 0")
        if not 0 <= self.heave_margin <= 1:
            raise ValueError(f"heave_margin = {self.heave_margin}: must be in [0, 1]")
        if not (self.rate_weight >= 0 and math.isfinite(self.rate_weight)):
            raise ValueError(f"rate_weight = {self.rate_weight} s^2: must be finite and >= 0")
        unknown = set(self.references) - set(REFERENCES)
        if unknown:
            raise ValueError(
                f"references = {self.references}: each must be one of {', '.join(REFERENCES)}"
            )

    @property
    def intervals(self) -> int:
        """Intervals of the plan over the horizon."""
        return round(self.horizon / self.interval)

    def check(self, scene) -> None:
        """Raise a ValueError naming the setting or scene field that does not fit the scene."""
        duration, plant_step = scene.numerics.duration, scene.numerics.step
        if self.horizon > duration:
            raise ValueError(
                f"horizon = {self.horizon} s: must be <= numerics.duration = {duration} s of "
                "the scene"
            )
        if not _multiple(duration, self.sample):
            raise ValueError(
                f"sample = {self.sample} s must divide numerics.duration = {duration} s into "
                "whole samples"
            )
        if not _multiple(self.sample, plant_step):
            raise ValueError(
                f"sample = {self.sample} s must be a whole multiple of the plant step "
                f"numerics.step = {plant_step} s"
            )
        if self.elements > scene.model.elements:
            raise ValueError(
                f"elements = {self.elements}: the reduced model needs 1 .. model.elements = "
                f"{scene.model.elements} elements"
            )
        if scene.model.torsion:
            raise ValueError("model.torsion = true: the MPC supports 5-DOF models only")
        if scene.top.heave_compensated:
            raise ValueError(
                "top.heave.compensation = true: the MPC compensates heave from measurements "
                "itself; set it to false"
            )

    def record(self) -> dict:
        """The settings as a result stores them (names with their units)."""
        units = {"horizon": "_s", "sample": "_s", "interval": "_s", "step": "_s",
                 "heave_filter": "_s", "rate_weight": "_s2", "limiter_band": "_rad"}  # fmt: skip
        out = {}
        for name, value in asdict(self).items():
            out[name + units.get(name, "")] = ",".join(value) if isinstance(value, tuple) else value
        return out
