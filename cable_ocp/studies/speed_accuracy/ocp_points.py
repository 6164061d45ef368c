"""The optimal-control part: each optimiser setting solved and verified."""

from __future__ import annotations

from dataclasses import dataclass

from cable_ocp.control.optimization import optimize
from cable_ocp.studies.speed_accuracy.plan import OcpSetting, StudyPlan
from cable_ocp.studies.speed_accuracy.timing import timed


@dataclass(frozen=True)
class OcpPoint:
    """One optimiser run on the OCP scene, verified on the scene's own model.

    Attributes
    ----------
    setting : OcpSetting
    omega : float, m
        Verified Omega (NaN when the last iterate could not be simulated).
    omega_model : float, m
        Omega on the optimisation model.
    success : bool
    status : str
    iterations, evaluations : int
    wall_time, cpu_time : float, s
        The whole ``optimize`` call, verification included.
    """

    setting: OcpSetting
    omega: float
    omega_model: float
    success: bool
    status: str
    iterations: int
    evaluations: int
    wall_time: float
    cpu_time: float


def ocp_point(scene, setting: OcpSetting, intervals: int, quiet: bool = True) -> OcpPoint:
    """Solve the OCP with one setting; Omega is verified on the scene's own model."""
    kwargs = {"refinements": setting.refinements} if setting.method == "ipopt" else {}
    settings = setting.settings(intervals)
    result, cpu, _ = timed(lambda: optimize(scene, settings=settings, quiet=quiet, **kwargs))
    return OcpPoint(
        setting=setting,
        omega=result.omega,
        omega_model=result.omega_model,
        success=result.success,
        status=result.status,
        iterations=result.iterations,
        evaluations=result.evaluations,
        wall_time=result.wall_time,
        cpu_time=cpu,
    )


def ocp_study(scene, plan: StudyPlan, quiet: bool = True) -> tuple[OcpPoint, ...]:
    """Every OCP setting of the plan on ``scene``."""
    return tuple(ocp_point(scene, s, plan.ocp_intervals, quiet) for s in plan.ocp)
