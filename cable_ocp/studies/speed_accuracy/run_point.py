"""One RK4 setting run and scored against the reference."""

from __future__ import annotations

import math
from dataclasses import dataclass

from cable_ocp.simulation.integrate import SimulationError
from cable_ocp.studies.speed_accuracy.model_setup import Setup
from cable_ocp.studies.speed_accuracy.plan import StudyPlan
from cable_ocp.studies.speed_accuracy.reference import Reference, end_error


@dataclass(frozen=True)
class RunPoint:
    """One measured RK4 setting.

    Attributes
    ----------
    elements : int
        ``n`` of the model.
    step : float, s
        The RK4 step h.
    torsion : bool
        Whether the model has torsion (6 DOF per element).
    mode : str
        ``"interpreted"`` or ``"compiled"``.
    stable : bool
        False when the run raised :class:`SimulationError`.
    error : float, m
        ``max_t |r_E - r_E,ref|`` at the output times (NaN when unstable).
    cpu_time, wall_time : float, s
        Of the integration alone (NaN when unstable): model build, equilibrium, compiling and
        building the step Function are excluded.
    steps : int
        RK4 steps of a complete run.
    message : str
        The failure, when unstable.
    """

    elements: int
    step: float
    torsion: bool
    mode: str
    stable: bool
    error: float
    cpu_time: float
    wall_time: float
    steps: int
    message: str = ""

    @property
    def label(self) -> str:
        """``n = 15, h = 0.0625 s, no torsion, compiled``."""
        twist = "torsion" if self.torsion else "no torsion"
        return f"n = {self.elements}, h = {self.step:g} s, {twist}, {self.mode}"


def measure(
    setup: Setup, step: float, mode: str, reference: Reference, plan: StudyPlan
) -> RunPoint:
    """Run one setting and score it against the reference; an unstable run is recorded as such."""
    compiled = mode == "compiled"
    steps = round(setup.scene.numerics.duration / step)
    point = dict(elements=setup.model.spec.elements, step=step, steps=steps, mode=mode)
    point["torsion"] = setup.scene.model.torsion
    try:
        # integrate keeps its Functions on the model: a run of one output interval first builds,
        # compiles or loads them all, so that only the integration is timed.
        setup.run(step, plan.output_interval, compiled, duration=plan.output_interval)
        _, end, cpu, wall = setup.run(step, plan.output_interval, compiled)
    except SimulationError as failure:
        return RunPoint(
            **point,
            stable=False,
            error=math.nan,
            cpu_time=math.nan,
            wall_time=math.nan,
            message=str(failure).split(". Remedy")[0],
        )
    return RunPoint(
        **point,
        stable=True,
        error=end_error(end, reference.end),
        cpu_time=cpu,
        wall_time=wall,
    )
