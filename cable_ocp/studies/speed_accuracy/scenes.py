"""Every measured setting of one scene: reference, step scans, Pareto front."""

from __future__ import annotations

import math
from dataclasses import dataclass

from cable_ocp.studies.speed_accuracy.model_setup import Setup
from cable_ocp.studies.speed_accuracy.pareto import pareto_front
from cable_ocp.studies.speed_accuracy.plan import StudyPlan
from cable_ocp.studies.speed_accuracy.reference import Reference, reference_run
from cable_ocp.studies.speed_accuracy.run_point import RunPoint, measure
from cable_ocp.studies.speed_accuracy.scan import first_step_guess, step_scan


@dataclass(frozen=True)
class SceneStudy:
    """Every measured setting of one scene against its reference.

    Attributes
    ----------
    scene_name : str
        The scene file's name in ``models_dir``, without ``.toml``.
    duration : float, s
        Simulated time of every run.
    constraint_tolerance : float, m
        Bond residual beyond which a run is stopped as failed.
    reference : Reference
        The converged end trajectory every point is measured against.
    points : tuple of RunPoint
        Every measured setting, stable or not.
    """

    scene_name: str
    duration: float
    constraint_tolerance: float
    reference: Reference
    points: tuple[RunPoint, ...]

    @property
    def stable_points(self) -> list[RunPoint]:
        """The points of complete runs."""
        return [p for p in self.points if p.stable]

    def pareto(self) -> list[RunPoint]:
        """Stable points not beaten in both CPU time and error, cheapest first."""
        stable = self.stable_points
        front = pareto_front([p.cpu_time for p in stable], [p.error for p in stable])
        return [stable[k] for k in front]

    def cheapest(self, tolerance: float) -> RunPoint | None:
        """The cheapest stable point with error <= ``tolerance`` (m), or None."""
        meeting = [p for p in self.stable_points if p.error <= tolerance]
        return min(meeting, key=lambda p: p.cpu_time) if meeting else None

    def stability_limits(self) -> list[tuple[int, bool, float, float]]:
        """``(n, torsion, largest stable step, smallest unstable step)`` (s; NaN if none)."""
        keys = sorted({(p.elements, p.torsion) for p in self.points})
        limits = []
        for n, torsion in keys:
            runs = [p for p in self.points if (p.elements, p.torsion) == (n, torsion)]
            stable = [p.step for p in runs if p.stable]
            unstable = [p.step for p in runs if not p.stable]
            limits.append(
                (n, torsion, max(stable, default=math.nan), min(unstable, default=math.nan))
            )
        return limits


def scene_study(scene, plan: StudyPlan, quiet: bool = True) -> SceneStudy:
    """Reference and grid of one scene (already cut to the study's duration)."""
    reference = reference_run(scene, plan)
    points: list[RunPoint] = []
    grid = [(n, False, plan.stable_steps) for n in plan.elements]
    grid += [(n, True, plan.torsion_stable_steps) for n in plan.torsion_elements]
    mode = "compiled" if plan.compiled else "interpreted"
    for n, torsion, count in grid:
        setup = Setup.build(scene, n, torsion)
        first = first_step_guess(scene, n, torsion, plan.output_interval)
        scanned = step_scan(
            lambda h, s=setup: measure(s, h, mode, reference, plan),
            first,
            plan.output_interval,
            count,
        )
        points += scanned
        if plan.compiled:
            affordable = [
                p for p in scanned if p.stable and (n + 1) * p.steps <= plan.interpreted_work
            ]
            points += [measure(setup, p.step, "interpreted", reference, plan) for p in affordable]
        if not quiet:
            print(f"{scene.name}: n = {n}, torsion {torsion}: done", flush=True)
    numerics = scene.numerics
    return SceneStudy(
        scene.name, numerics.duration, numerics.constraint_tolerance, reference, tuple(points)
    )
