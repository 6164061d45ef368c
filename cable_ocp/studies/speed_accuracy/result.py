"""The result of the whole speed-accuracy study."""

from __future__ import annotations

from dataclasses import dataclass

from cable_ocp.studies.speed_accuracy.ocp_points import OcpPoint
from cable_ocp.studies.speed_accuracy.plan import StudyPlan
from cable_ocp.studies.speed_accuracy.scenes import SceneStudy


@dataclass(frozen=True)
class SpeedAccuracy:
    """The whole study.

    Attributes
    ----------
    plan : StudyPlan
        What was measured.
    scenes : tuple of SceneStudy
        The simulation part, one per scene of the plan.
    ocp : tuple of OcpPoint
        The OCP part, one per optimiser setting.
    ocp_scene : str
        Name of the scene the OCP part solves.
    ocp_duration : float, s
        Its horizon.
    cpu_time, wall_time : float, s
        Of the whole study, compiling included.
    """

    plan: StudyPlan
    scenes: tuple[SceneStudy, ...]
    ocp: tuple[OcpPoint, ...]
    ocp_scene: str
    ocp_duration: float
    cpu_time: float
    wall_time: float
