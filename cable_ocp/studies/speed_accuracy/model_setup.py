"""The study's scenes and models at rest, ready to integrate with RK4 (locked winch)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cable_ocp.drive import winch
from cable_ocp.drive.drive import Drive
from cable_ocp.model.cable import CableModel
from cable_ocp.simulation.integrate import integrate
from cable_ocp.simulation.statics import equilibrium
from cable_ocp.studies.speed_accuracy.plan import StudyPlan
from cable_ocp.studies.speed_accuracy.timing import timed
from cable_ocp.studies.uniform import locked_uniform


def study_scene(scene, plan: StudyPlan, duration: float):
    """The scene over ``duration`` (s) on the uniform mesh of every n of the plan (locked winch)."""
    counts = (*plan.elements, *plan.torsion_elements, plan.reference_elements)
    return locked_uniform(scene, counts, {"numerics.duration": duration})


@dataclass(frozen=True)
class Setup:
    """A model at rest, ready to integrate: scene, model, drive and initial state."""

    scene: object
    model: CableModel
    drive: Drive
    x0: np.ndarray

    @classmethod
    def build(cls, scene, elements: int, torsion: bool = False) -> Setup:
        """The locked-winch ``scene`` with ``elements`` and torsion, at its static equilibrium."""
        local = scene.updated({"model.elements": elements, "model.torsion": torsion})
        model = CableModel.from_scene(local)
        drive = Drive.from_scene(local, winch.locked, elements=elements)
        return cls(local, model, drive, equilibrium(model, drive).state)

    def run(
        self, step: float, output_interval: float, compiled: bool, duration: float | None = None
    ):
        """RK4 end trajectory sampled every ``output_interval`` (s); CPU and wall time (s).

        ``duration`` (s) defaults to the scene's.
        """
        numerics = self.scene.numerics
        raw, cpu, wall = timed(
            lambda: integrate(
                self.model,
                self.x0,
                self.drive,
                duration or numerics.duration,
                step,
                output_every=round(output_interval / step),
                tolerance=numerics.constraint_tolerance,
                compiled=compiled,
            )
        )
        return raw.time, raw.states[:, :3], cpu, wall
