"""The closed loop's settings, one dataclass built alike by the API and the CLI, checked once."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, replace

import numpy as np

from cable_ocp.control import defaults
from cable_ocp.control.checks import Rule, check_fields
from cable_ocp.control.gauss_newton import GaussNewtonSettings
from cable_ocp.control.ipopt import IpoptSettings
from cable_ocp.control.settings import ModelSettings
from cable_ocp.control.solvers import DEFAULT_SOLVER, SOLVERS, solver_of
from cable_ocp.drive.bounds import angle_bounds

# Targets (s) of the derived timing: a solve every second, plan intervals of 5 s (1 s intervals
# let the plan exploit the reduced model's errors, ``interval`` below), a 20 s horizon.
SAMPLE, INTERVAL, HORIZON = 1.0, defaults.CONTROL_INTERVAL, 20.0
# The controller's model: 2 elements, its step at most 1 s (what served the paper's rope; its
# limit along the run is above 1.4 s there).
CONTROLLER_ELEMENTS, CONTROLLER_STEP_CAP = 2, 1.0
# rad: the plant's soft limiter band when the range allows (``limiter_band`` below).
LIMITER_BAND = 0.5
# The solvers the closed loop may run, and their settings when none are given (the registry's).
CLOSED_LOOP_SOLVERS = {
    name: entry.closed_loop_settings for name, entry in SOLVERS.items() if entry.closed_loop
}


def _multiple(value: float, unit: float) -> bool:
    """Whether ``value`` is a whole multiple of ``unit`` (to round-off)."""
    count = round(value / unit)
    return count >= 1 and abs(count * unit - value) <= 1e-9 * max(abs(value), 1.0)


def _dividing_interval(horizon: float, sample: float, wanted: float) -> float:
    """The multiple of ``sample`` nearest ``wanted`` (s) that divides a fixed ``horizon`` (s).

    The sample itself when the horizon is no multiple of it (the timing check then says so).
    """
    samples = round(horizon / sample)
    counts = [m for m in range(1, samples + 1) if samples % m == 0] or [1]
    return sample * min(counts, key=lambda m: abs(m * sample - wanted))


_RULES = {
    "horizon": Rule("number", above=0, unit="s", optional=True),
    "sample": Rule("number", above=0, unit="s", optional=True),
    "interval": Rule("number", above=0, unit="s", optional=True),
    "first_interval": Rule("number", above=0, unit="s", optional=True),
    "solver": Rule("choice", choices=tuple(CLOSED_LOOP_SOLVERS)),
    "heave_feedback": Rule("flag"),
    "heave_filter": Rule("number", above=0, unit="s"),
    "heave_margin": Rule("number", low=0, high=1),
    "limiter_band": Rule("number", above=0, unit="rad", optional=True),
    "rate_weight": Rule("number", low=0, unit="s^2"),
}


@dataclass(frozen=True)
class MpcSettings:
    """How the receding-horizon controller is built and run.

    Attributes
    ----------
    horizon : float or None, s
        Prediction horizon; a multiple of ``interval``, at most the scene's duration (None:
        about 20 s).
    sample : float or None, s
        Time between solves; a multiple of the plant's step and of ``step`` (None: the
        duration's whole fraction nearest 1 s that the plant's steps divide).
    interval : float or None, s
        Length of one interval of the plan (its Hermite nodes are this far apart); divides
        ``horizon``. Plans of 1 s intervals, re-solved every second, have the freedom to exploit
        the reduced model's errors: on the README's heave case Omega was 0.168 m with 1 s
        intervals against 0.046 m with 5 s ones (a 1 s sample, h = 1 s, converged solves).
        None: the multiple of ``sample`` nearest 5 s.
    first_interval : float or None, s
        Length of the plan's first interval, the one the next samples apply: the plan's nodes
        are 0, ``first_interval``, then the multiples of ``interval`` after it (move blocking:
        dense where the plan acts, coarse beyond). At most ``interval`` and a whole multiple of
        ``step``; None: ``interval`` (equal intervals). One sample roughly halves Omega where
        the winch can follow the hill: on the robustness bench's 44 heaving ``paper_hill``
        scenes (seeds 0 and 1) Omega was 0.47 of the equal intervals' (median; never higher),
        0.59 with two samples, all 43 runs that succeeded before succeeding. It is not the
        default because its sharper first second breaks marginal deep scenes: on the 28
        heaving whole-space scenes among the first 30 of seeds 0 and 1, 18 runs succeeded
        against 23 (a rope that pushes, the drum past its bound; 21 with two samples), and
        Omega was 0.999 of the equal intervals' (median; 8.2 times at worst). Measured
        2026-12-06.
    model : ModelSettings
        The controller's model: its elements (None: 2) and RK4 step (None: the largest whole
        fraction of ``sample`` within 0.7 of the controller model's RK4 limit along the scene's
        locked run, at most 1 s, :mod:`cable_ocp.control.defaults`); a step above that limit is
        refused.
    solver : str
        ``"gauss-newton"``: Gauss-Newton steps from the shifted previous plan (by default one
        per sample, a real-time iteration: one simulation with sensitivities and one QP);
        ``"ipopt"``: IPOPT with a limited-memory Hessian on the multiple-shooting NLP,
        warm-started.
    solver_settings : GaussNewtonSettings or IpoptSettings or None
        That solver's own settings (None: :data:`CLOSED_LOOP_SOLVERS`).
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
    limiter_band : float or None, rad
        Width of the plant's soft limiter at each end of the winch range (the plan keeps clear
        of it too); None: 0.5 rad, or a quarter of a narrower range. At most half the range.
        Its bend accelerates the winch by about ``rate^2 / band``: at 0.2 rad (the earlier
        value) the heave feedback bent into a bound opened the plant's bonds by 1.4e-4 to
        3.6e-4 m on 5 of 35 heaving robustness scenes (seeds 0 and 3, 1 s sample); at 0.5 rad
        on 1.
    rate_weight : float, s^2
        Weight of the pay-out speed ``(r_D phi')^2`` against ``e^2`` in the objective.
    """

    horizon: float | None = None
    sample: float | None = None
    interval: float | None = None
    first_interval: float | None = None
    model: ModelSettings = field(default_factory=ModelSettings)
    solver: str = DEFAULT_SOLVER
    solver_settings: GaussNewtonSettings | IpoptSettings | None = None
    heave_feedback: bool = True
    heave_filter: float = 15.0
    heave_margin: float = 0.5
    limiter_band: float | None = None
    rate_weight: float = 1e-4

    def __post_init__(self):
        check_fields(self, _RULES)
        if not isinstance(self.model, ModelSettings):
            raise ValueError(f"MpcSettings.model = {self.model!r:.60}: a ModelSettings")
        solver_of(self.solver, self.solver_settings, closed_loop=True)
        if None not in (self.horizon, self.sample, self.interval, self.step):
            self._check_timing()

    def _check_timing(self) -> None:
        """The horizon, sample, interval and step fit together (ValueError naming the setting)."""
        sample, horizon, step = self.sample, self.horizon, self.step
        if not horizon > sample:
            raise ValueError(f"horizon = {horizon} s: must be > sample = {sample} s")
        if not _multiple(horizon, sample):
            raise ValueError(
                f"horizon = {horizon} s must be a whole multiple of sample = {sample} s"
            )
        if not _multiple(sample, step):
            raise ValueError(f"step = {step} s: must divide sample = {sample} s")
        if not _multiple(horizon, self.interval):
            raise ValueError(f"interval = {self.interval} s: must divide horizon = {horizon} s")
        if not _multiple(self.interval, step):
            raise ValueError(f"step = {step} s: must divide interval = {self.interval} s")
        first = self.first_interval
        if first is not None:
            if first > self.interval * (1 + 1e-9):
                raise ValueError(
                    f"first_interval = {first} s: must be at most interval = {self.interval} s"
                )
            if not _multiple(first, step):
                raise ValueError(f"step = {step} s: must divide first_interval = {first} s")

    def resolved(self, scene, compiled: bool = True) -> tuple[MpcSettings, str]:
        """The settings with the timing left unset derived from the scene, and how (a phrase).

        Checked against the scene (:meth:`check`); a fixed controller step above its model's
        RK4 limit along the locked run is refused.
        """
        duration, plant_step = scene.numerics.duration, scene.numerics.step
        notes = []
        sample = self.sample
        if sample is None:
            samples = defaults.intervals_for(duration, plant_step, round(duration / SAMPLE))
            sample = duration / samples
            notes.append(f"sample {sample:.4g} s")
        interval = self.interval
        if interval is None:
            interval = sample * max(1, round(INTERVAL / sample))
            interval = min(interval, sample * max(1, math.floor(duration / sample + 1e-9)))
            if self.horizon is not None and not _multiple(self.horizon, interval):
                interval = _dividing_interval(self.horizon, sample, interval)
            notes.append(f"plan intervals of {interval:.4g} s")
        horizon = self.horizon
        if horizon is None:
            horizon = interval * max(1, round(HORIZON / interval))
            if horizon > duration * (1 + 1e-9):
                horizon = interval * max(1, math.floor(duration / interval + 1e-9))
            if horizon <= sample * (1 + 1e-9):
                horizon = 2 * sample
            notes.append(f"horizon {horizon:.4g} s")
        first = interval if self.first_interval is None else self.first_interval
        band = self.limiter_band
        if band is None:
            low, high = angle_bounds(scene)
            band = min(LIMITER_BAND, (high - low) / 4)
            if band < LIMITER_BAND:
                notes.append(f"limiter band {band:.3g} rad (a quarter of the winch range)")
        step, elements = self.step, self.elements
        if elements > scene.model.elements:
            raise ValueError(
                f"model.elements = {elements}: the controller's model needs 1 .. "
                f"model.elements = {scene.model.elements} elements of the scene"
            )
        step, derived = defaults.model_step(
            scene, elements, step, sample, CONTROLLER_STEP_CAP, compiled, "model.step",
            f"controller of {elements} elements at",
        )  # fmt: skip
        notes += derived
        solver, solver_settings = solver_of(self.solver, self.solver_settings, closed_loop=True)
        if self.solver_settings is None:
            solver_settings = solver.closed_loop_settings
        chosen = replace(
            self,
            horizon=horizon,
            sample=sample,
            interval=interval,
            first_interval=first,
            model=ModelSettings(elements, step),
            limiter_band=band,
            solver=solver.name,
            solver_settings=solver_settings,
        )
        chosen.check(scene)
        return chosen, ("derived settings: " + ", ".join(notes)) if notes else ""

    @property
    def elements(self) -> int:
        """Elements of the controller's model (``model.elements``, or 2)."""
        return self.model.elements or CONTROLLER_ELEMENTS

    @property
    def step(self) -> float | None:
        """The controller model's RK4 step, s (``model.step``)."""
        return self.model.step

    @property
    def intervals(self) -> int:
        """Intervals of ``interval`` over the horizon (the IPOPT path's shooting intervals)."""
        return round(self.horizon / self.interval)

    @property
    def plan_nodes(self) -> np.ndarray:
        """The plan's node times (s) over the horizon (``first_interval``; resolved settings)."""
        later = self.interval * np.arange(1, self.intervals + 1)
        first = self.first_interval
        if first is None or first >= later[0] * (1 - 1e-9):
            return np.concatenate([[0.0], later])
        return np.concatenate([[0.0, first], later])

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
                f"model.elements = {self.elements}: the controller's model needs 1 .. "
                f"model.elements = {scene.model.elements} elements of the scene"
            )
        if scene.model.torsion:
            raise ValueError("model.torsion = true: the MPC supports 5-DOF models only")
        low, high = angle_bounds(scene)
        if self.limiter_band is not None and self.limiter_band > (high - low) / 2:
            raise ValueError(
                f"limiter_band = {self.limiter_band:g} rad: must be at most half the winch range "
                f"[winch.angle_min, winch.angle_max] = [{low:g}, {high:g}] rad, "
                f"{(high - low) / 2:g} rad (leave it unset to derive it)"
            )
        self._check_timing()
        if scene.top.heave_compensated:
            raise ValueError(
                "top.heave.compensation = true: the MPC compensates heave from measurements "
                "itself; set it to false"
            )

    def record(self) -> dict:
        """The settings as a result stores them (nested tables; units as documented above)."""
        out = {}
        for name, value in asdict(self).items():
            out[name] = ",".join(value) if isinstance(value, tuple) else value
        return out

    @classmethod
    def from_record(cls, record: dict) -> MpcSettings:
        """The settings a result kept (:meth:`record`, with what the loop added), checked again.

        Raises
        ------
        ValueError
            Naming the record, when it is not one (files written before the settings were split
            keep other keys: rerun those with the settings of their time).
        """
        names = [f for f in cls.__dataclass_fields__ if f in record]
        try:
            fields = {name: record[name] for name in names}
            # Results written before the first interval was a setting planned on equal ones.
            fields.setdefault("first_interval", record.get("interval"))
            fields["model"] = ModelSettings(**record["model"])
            solver = record["solver"]
            if record.get("solver_settings") is not None:
                fields["solver_settings"] = SOLVERS[solver].settings(**record["solver_settings"])
            return cls(**fields)
        except (KeyError, TypeError) as error:
            raise ValueError(
                f"settings {record!r:.80}: not a record of MpcSettings ({type(error).__name__}: "
                f"{error})"
            ) from None
