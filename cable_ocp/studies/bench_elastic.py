"""``cable-ocp bench elastic``: the elastic rope beside the rigid one and MoorDyn on a deep lift.

The deep case ``steel_2000m_40t`` of :mod:`cable_ocp.studies.moordyn_deep` (40 t on 2000 m of
40 mm steel wire, T0 = 5.7 s, H_s 2 m, winch locked, 800 s): each model's wall time per simulated
second of the whole run (warm: built and compiled before), its real-time factor, and its figures
(payload heave std, top tension range) against MoorDyn's, so that speed is read at a stated
accuracy. The elastic rope runs at n = 50 (the acceptance's size) and at n = 10, where doubling n
moves no figure by 0.5 %, at h = 0.05 s and at h = 0.1 s (57 steps a period of T0, sampled every
0.1 s); the rigid rope at the same sizes is the baseline that is fast and wrong.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from cable_ocp.studies import elastic_deep as ed
from cable_ocp.studies import moordyn_deep as md

CASE = "steel_2000m_40t"
# (n, h in s) of the project's runs, each for both ropes.
RUNS = ((50, ed.STEP), (ed.ELEMENTS, ed.STEP), (ed.ELEMENTS, 2 * ed.STEP))


@dataclass(frozen=True)
class ElasticTiming:
    """One model's run of the deep case.

    Attributes
    ----------
    label : str
        The model and its settings as the table prints them (rope, n, h; or MoorDyn's
        segments and step).
    figures : HeaveFigures
        Payload heave and top tension figures of the run.
    milliseconds_per_simulated_second : float, ms/s
        Wall time of the whole run per simulated second.
    """

    label: str
    figures: md.HeaveFigures
    milliseconds_per_simulated_second: float

    @property
    def real_time_factor(self) -> float:
        """Simulated seconds per wall second."""
        return 1e3 / self.milliseconds_per_simulated_second


def _project(case: md.DeepCase, elements: int, step: float, axial: str) -> ElasticTiming:
    scene = ed.case_scene(case, elements=elements, step=step)
    scene = replace(scene, model=replace(scene.model, axial=axial))
    figures, wall = ed.heave_run(scene)
    per_second = 1e3 * wall / scene.numerics.duration
    return ElasticTiming(f"{axial}, n = {elements}, h = {step:g} s", figures, per_second)


def _moordyn(case: md.DeepCase) -> ElasticTiming:
    scene = case.scene()
    run = md.heave_run(scene, case.segments)
    figures = md.heave_figures(run.time, run.top, run.payload, run.tension)
    label = f"MoorDyn, {case.segments} segments, {run.internal_step:g} s"
    return ElasticTiming(label, figures, run.ms_per_simulated_second)


def measure(case_name: str = CASE) -> list[ElasticTiming]:
    """The elastic and rigid ropes at :data:`RUNS`, then MoorDyn (if installed), on one case."""
    case = next(case for case in md.CASES if case.name == case_name)
    timings = [_project(case, *run, axial) for axial in ("elastic", "rigid") for run in RUNS]
    try:
        timings.append(_moordyn(case))
    except ImportError:
        print("MoorDyn is not installed (pip install -e '.[bench]'): its row is left out")
    return timings


def report(models_dir=None, quick: bool = False) -> list[ElasticTiming]:
    """Print the table of :func:`measure` with the ratios to MoorDyn.

    ``models_dir`` and ``quick`` are the bench's common arguments, unused: the case is fixed
    (800 s simulated, about a minute in all).
    """
    timings = measure()
    reference = timings[-1] if timings[-1].label.startswith("MoorDyn") else None
    print(f"\nElastic rope on the deep lift {CASE} (T0 5.7 s, Hs 2 m, winch locked, 800 s)")
    print(
        f"{'model':<34} {'ms/sim s':>9} {'x real time':>12} {'heave std m':>12} "
        f"{'range kN':>9} {'vs MoorDyn':>22} {'speed vs MoorDyn':>17}"
    )
    for timing in timings:
        figures = timing.figures
        against, speed = "", ""
        if reference is not None and timing is not reference:
            heave = figures.payload_heave_std / reference.figures.payload_heave_std - 1
            tension = figures.tension_range / reference.figures.tension_range - 1
            against = f"{heave:+.1%} / {tension:+.1%}"
            ratio = reference.milliseconds_per_simulated_second
            speed = f"{ratio / timing.milliseconds_per_simulated_second:.2f}x"
        print(
            f"{timing.label:<34} {timing.milliseconds_per_simulated_second:9.2f} "
            f"{timing.real_time_factor:12.0f} {figures.payload_heave_std:12.4f} "
            f"{figures.tension_range / 1e3:9.1f} {against:>22} {speed:>17}"
        )
    return timings
