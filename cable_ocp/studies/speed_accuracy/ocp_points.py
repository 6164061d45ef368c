"""The optimal-control part: each optimiser setting solved and verified."""

from __future__ import annotations

from dataclasses import dataclass

from cable_ocp.control.optimization import OcpResult, optimize
from cable_ocp.studies.solve_record import kept
from cable_ocp.studies.speed_accuracy.plan import OcpSetting, StudyPlan
from cable_ocp.studies.speed_accuracy.timing import timed


@dataclass(frozen=True)
class OcpPoint:
    """One optimiser run on the OCP scene, Omega verified on the scene's own model.

    Attributes
    ----------
    setting : OcpSetting
        The optimiser setting that ran.
    cpu_time : float, s
        Of the whole ``optimize`` call, verification included.
    result : OcpResult
        What ``optimize`` returned, its figures (``omega``, ``success``, ``wall_time``, ...)
        without the verified trajectory (:func:`~cable_ocp.studies.solve_record.kept`).
    """

    setting: OcpSetting
    cpu_time: float
    result: OcpResult


def ocp_point(scene, setting: OcpSetting, intervals: int, quiet: bool = True) -> OcpPoint:
    """Solve the OCP with one setting; Omega is verified on the scene's own model."""
    settings, options = setting.settings(intervals), setting.options
    result, cpu, _ = timed(lambda: optimize(scene, settings=settings, quiet=quiet, **options))
    return OcpPoint(setting=setting, cpu_time=cpu, result=kept(result))


def ocp_study(scene, plan: StudyPlan, quiet: bool = True) -> tuple[OcpPoint, ...]:
    """Every OCP setting of the plan on ``scene``."""
    return tuple(ocp_point(scene, s, plan.ocp_intervals, quiet) for s in plan.ocp)
