"""The project's elastic rope on the deep cases of :mod:`cable_ocp.studies.moordyn_deep`.

The same scene, vessel motion and statistics as MoorDyn's reference runs: a payload hanging on a
vertical line from a heaving vessel with the winch locked (the heave figures after
:data:`~cable_ocp.studies.moordyn_deep.SETTLE`), and a free decay after the top is lifted by
:data:`~cable_ocp.studies.moordyn_deep.DECAY_LIFT` (the axial period). Issue 44, acceptance 1;
``tests/test_elastic_moordyn.py`` holds the rows of VALIDATION.md and ``cable-ocp bench`` the speed.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

from cable_ocp.drive.drive import Drive
from cable_ocp.model.cable import CableModel
from cable_ocp.scene.schema import Scene
from cable_ocp.simulation.integrate import integrate
from cable_ocp.simulation.run import simulate
from cable_ocp.simulation.statics import starting_state
from cable_ocp.studies import moordyn_deep as md

ELEMENTS = 10  # n of the project's model on a deep case: doubling it moves no figure by 0.5 %
STEP = 0.05  # s, RK4 step: the records' sampling (halving it moves no figure by 0.1 %)
# The heave runs' largest bond residual (m): 0.1 mm on lines of 500-3000 m, as deep_lift's
# (hanging's 1e-6 m was set for 300 m of line at h = 0.05 s).
BOND_TOLERANCE = 1e-4
# The free decay's largest bond residual (m): the lift's 4 m/s^2 drifts the bonds of the rigid and
# the elastic chain alike, by 6e-4 m at h = 0.05 s (6e-5 m at 0.0125 s) on 500 m of line.
DECAY_BOND_TOLERANCE = 1e-3


@dataclass(frozen=True)
class ElasticRun:
    """The project's model on one deep case.

    Attributes
    ----------
    figures : HeaveFigures
        Heave and top tension statistics under the sea state, winch locked.
    decay_period : float, s
        The axial period from the free decay.
    wall_time : float, s
        Of the heave run (the model already built and compiled).
    duration : float, s
        Simulated by the heave run.
    """

    figures: md.HeaveFigures
    decay_period: float
    wall_time: float
    duration: float

    @property
    def ms_per_simulated_second(self) -> float:
        """Wall time per simulated second of the heave run, ms/s."""
        return 1e3 * self.wall_time / self.duration


def case_scene(
    case: md.DeepCase, heave: bool = True, elements: int = ELEMENTS, step: float = STEP
) -> Scene:
    """The case as a scene at ``elements`` and ``step`` (s), sampled every max(0.05 s, step)."""
    scene = case.scene(heave=heave, elements=elements)
    every = max(1, round(md.COUPLING_STEP / step))
    numerics = replace(
        scene.numerics, step=step, output_every=every, constraint_tolerance=BOND_TOLERANCE
    )
    return replace(scene, numerics=numerics)


def heave_run(scene: Scene) -> tuple[md.HeaveFigures, float]:
    """Heave figures of the scene's run on the project's model, and its wall time (s), warm."""
    simulate(scene, compiled=True)  # builds and compiles the model once
    started = time.perf_counter()
    run = simulate(scene, compiled=True)
    wall = time.perf_counter() - started
    figures = md.heave_figures(run.time, run.top[:, 2], run.end[:, 2], run.top_tension)
    return figures, wall


def decay_period(scene: Scene) -> float:
    """Axial period (s) of the project's model in MoorDyn's free decay (:func:`md.decay_top`).

    ``scene``: the case without heave (``case_scene(case, heave=False)``), whose rope is made
    elastic (without heave, ``auto`` would keep it rigid: nothing excites it).
    """
    scene = replace(scene, model=replace(scene.model, axial="elastic"))
    period = md.axial_period(scene)
    model = CableModel.from_scene(scene)
    drive = replace(Drive.from_scene(scene), top=md.decay_top(scene))
    duration = round((md.DECAY_PERIODS + 0.5) * period / md.COUPLING_STEP) * md.COUPLING_STEP
    every = max(1, round(md.COUPLING_STEP / scene.numerics.step))
    raw = integrate(
        model,
        starting_state(model, drive, compiled=True),
        drive,
        duration,
        scene.numerics.step,
        output_every=every,
        tolerance=DECAY_BOND_TOLERANCE,
        compiled=True,
    )
    top = md.decay_top(scene)(raw.time)[0][2]
    return md.decay_period(raw.time, top, raw.states[:, 2])  # z of A_0, the payload


def elastic_run(case: md.DeepCase, elements: int = ELEMENTS, step: float = STEP) -> ElasticRun:
    """The project's elastic rope on ``case``: heave figures, decay period and speed."""
    scene = case_scene(case, elements=elements, step=step)
    figures, wall = heave_run(scene)
    period = decay_period(case_scene(case, heave=False, elements=elements, step=step))
    return ElasticRun(figures, period, wall, scene.numerics.duration)
