"""Speed against accuracy: end-trajectory error versus CPU time, and OCP Omega versus wall time.

For each scene (``paper_flat`` with the winch locked, ``end_force``) a reference end trajectory
comes from the adaptive DOP853 integrator
(:func:`cable_ocp.simulation.integrate.reference_solution`) on the compiled right-hand side of a
fine model; its own uncertainty is its difference from an RK4 run of the same model at a small step.
Every other setting (elements ``n``, RK4 step ``h``, torsion on or off, interpreted or compiled) is
scored by ``max_t |r_E - r_E,ref|`` against the CPU time of its integration. For each ``n`` the step
is doubled until a run fails (:class:`SimulationError`), which brackets the RK4 stability limit; the
failed run is recorded as unstable. The optimal-control part solves ``paper_flat`` by IPOPT on
reduced models and by Nelder-Mead, each verified on the scene's own model (CONVENTIONS.md §5, §8).

The entry point is :func:`run_speed_accuracy`.

Modules, one job each:

- ``plan``: what is measured (:class:`StudyPlan`, :class:`OcpSetting`, the full and quick plans);
- ``model_setup``: the scenes and models at rest (:func:`study_scene`, :class:`Setup`);
- ``reference``: the reference end trajectory (:func:`reference_run`, :func:`end_error`);
- ``run_point``: one RK4 setting, run and scored (:func:`measure`);
- ``scan``: the step scan around the stability limit (:func:`step_scan`);
- ``scenes``: every setting of one scene (:func:`scene_study`);
- ``pareto``: the Pareto front (:func:`pareto_front`);
- ``ocp_points``: the optimal-control part (:func:`ocp_study`);
- ``result``: the whole study's result (:class:`SpeedAccuracy`);
- ``charts`` and ``markdown``: the figures and the report;
- ``study``: the front door (:func:`run_speed_accuracy`);
- ``timing``: CPU and wall time of a call (:func:`timed`).
"""

from cable_ocp.studies.speed_accuracy.charts import MARKERS, ocp_chart, speed_chart
from cable_ocp.studies.speed_accuracy.markdown import ocp_report, report, scene_report
from cable_ocp.studies.speed_accuracy.model_setup import Setup, study_scene
from cable_ocp.studies.speed_accuracy.ocp_points import OcpPoint, ocp_point, ocp_study
from cable_ocp.studies.speed_accuracy.pareto import pareto_front
from cable_ocp.studies.speed_accuracy.plan import (
    FULL_PLAN,
    QUICK_PLAN,
    TOLERANCES,
    OcpSetting,
    StudyPlan,
)
from cable_ocp.studies.speed_accuracy.reference import Reference, end_error, reference_run
from cable_ocp.studies.speed_accuracy.result import SpeedAccuracy
from cable_ocp.studies.speed_accuracy.run_point import RunPoint, measure
from cable_ocp.studies.speed_accuracy.scan import SMALLEST_STEP, first_step_guess, step_scan
from cable_ocp.studies.speed_accuracy.scenes import SceneStudy, scene_study
from cable_ocp.studies.speed_accuracy.study import run_speed_accuracy
from cable_ocp.studies.speed_accuracy.timing import timed

__all__ = [
    "FULL_PLAN",
    "MARKERS",
    "OcpPoint",
    "OcpSetting",
    "QUICK_PLAN",
    "Reference",
    "RunPoint",
    "SMALLEST_STEP",
    "SceneStudy",
    "Setup",
    "SpeedAccuracy",
    "StudyPlan",
    "TOLERANCES",
    "end_error",
    "first_step_guess",
    "measure",
    "ocp_chart",
    "ocp_point",
    "ocp_report",
    "ocp_study",
    "pareto_front",
    "reference_run",
    "report",
    "run_speed_accuracy",
    "scene_report",
    "scene_study",
    "speed_chart",
    "step_scan",
    "study_scene",
    "timed",
]
