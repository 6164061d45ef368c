"""The front door of the speed-accuracy study: run it, write report and charts."""

from __future__ import annotations

import time
from pathlib import Path

from cable_ocp.scene.output import atomic_directory
from cable_ocp.scene.schema import load_scene
from cable_ocp.studies.speed_accuracy.charts import ocp_chart, speed_chart
from cable_ocp.studies.speed_accuracy.markdown import report
from cable_ocp.studies.speed_accuracy.model_setup import study_scene
from cable_ocp.studies.speed_accuracy.ocp_points import ocp_study
from cable_ocp.studies.speed_accuracy.plan import FULL_PLAN, QUICK_PLAN
from cable_ocp.studies.speed_accuracy.result import SpeedAccuracy
from cable_ocp.studies.speed_accuracy.scenes import scene_study


def run_speed_accuracy(
    out: Path, models_dir: Path, quick: bool = False, quiet: bool = True
) -> SpeedAccuracy:
    """Measure speed against accuracy and write the report and charts into ``out`` atomically.

    Parameters
    ----------
    out : Path
        Folder of ``speed_accuracy.md``, ``speed_accuracy_<scene>.png`` and
        ``ocp_omega_vs_time.png`` (replaced as a whole).
    models_dir : Path
        Folder of the scene files.
    quick : bool
        A tiny version (n = 3, 5 against n = 5, seconds of simulated time, a one-iteration OCP).
    quiet : bool
        No progress messages.

    Returns
    -------
    SpeedAccuracy
    """
    plan = QUICK_PLAN if quick else FULL_PLAN
    cpu, wall = time.process_time(), time.perf_counter()
    scenes = []
    for name, duration in plan.scenes:
        scene = study_scene(load_scene(Path(models_dir) / f"{name}.toml"), plan, duration)
        scenes.append(scene_study(scene, plan, quiet))
    ocp_scene = load_scene(Path(models_dir) / "paper_flat.toml")
    if plan.ocp_duration is not None:
        ocp_scene = ocp_scene.updated({"numerics.duration": plan.ocp_duration})
    ocp = ocp_study(ocp_scene, plan, quiet)
    result = SpeedAccuracy(
        plan=plan,
        scenes=tuple(scenes),
        ocp=ocp,
        ocp_scene=ocp_scene.name,
        ocp_duration=ocp_scene.numerics.duration,
        cpu_time=time.process_time() - cpu,
        wall_time=time.perf_counter() - wall,
    )
    with atomic_directory(out) as folder:
        for study in result.scenes:
            speed_chart(study, folder / f"speed_accuracy_{study.scene_name}.png")
        if result.ocp:
            ocp_chart(result.ocp, result.ocp_scene, folder / "ocp_omega_vs_time.png")
        (folder / "speed_accuracy.md").write_text(report(result))
    return result
