"""Benchmarks that print their figures next to a baseline measured or quoted in the same run.

``cable-ocp bench`` times the RK4 step of the interpreted model (CasADi's SX virtual machine) at
n = 15 on ``paper_flat`` and n = 100 on ``end_force``, and sets the wall time per simulated second
beside the paper's (5242 s for 100 s at n = 100, h = 2e-4 s).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from cable_ocp.drive import Drive
from cable_ocp.integrate import rk4_step, stage_inputs
from cable_ocp.model import CableModel
from cable_ocp.scene import load_scene
from cable_ocp.statics import equilibrium

PAPER_WALL_TIME = 5242.0  # s, for 100 s simulated at n = 100 (paper §4.2)
PAPER_SIMULATED = 100.0  # s
PAPER_STEP = 2e-4  # s


@dataclass(frozen=True)
class StepTiming:
    """Cost of RK4 steps of one model.

    Attributes
    ----------
    scene : str
    elements : int
    step : float, s
    build_time : float, s
        Building the symbolic model and the step Function.
    microseconds_per_step : float, us
    wall_per_simulated_second : float, s/s
    """

    scene: str
    elements: int
    step: float
    build_time: float
    microseconds_per_step: float
    wall_per_simulated_second: float


def time_rk4(scene_path: Path, elements: int, steps: int, repeats: int = 3) -> StepTiming:
    """Time ``steps`` RK4 steps of a scene's model in one mapaccum (best of ``repeats``)."""
    scene = load_scene(scene_path, {"model.elements": elements})
    started = time.perf_counter()
    model = CableModel.from_scene(scene)
    step = scene.numerics.step
    run = rk4_step(model, step).mapaccum(steps)
    build = time.perf_counter() - started
    drive = Drive.from_scene(scene)
    x0 = equilibrium(model, drive)
    inputs = stage_inputs(drive, np.arange(steps) * step, step)
    best = np.inf
    for _ in range(repeats):
        started = time.perf_counter()
        run(x0, inputs)
        best = min(best, time.perf_counter() - started)
    per_step = best / steps
    return StepTiming(scene.name, elements, step, build, 1e6 * per_step, per_step / step)


def rk4_report(models_dir: Path, quick: bool = False) -> list[StepTiming]:
    """Print the RK4 benchmark and return its timings."""
    cases = [("paper_flat.toml", 15, 400), ("end_force.toml", 100, 100 if quick else 300)]
    timings = [time_rk4(models_dir / name, n, steps) for name, n, steps in cases]
    paper_per_second = PAPER_WALL_TIME / PAPER_SIMULATED
    paper_per_step = PAPER_WALL_TIME / (PAPER_SIMULATED / PAPER_STEP)
    print("RK4 step, interpreted (CasADi SX virtual machine), best of 3")
    print(f"{'scene':<12}{'n':>5}{'h [s]':>9}{'build [s]':>11}{'us/step':>11}"
          f"{'wall/sim s':>13}{'paper/ours':>12}")  # fmt: skip
    for t in timings:
        ratio = (
            f"{paper_per_second / t.wall_per_simulated_second:>12.0f}" if t.elements == 100 else ""
        )
        print(
            f"{t.scene:<12}{t.elements:>5}{t.step:>9.3g}{t.build_time:>11.2f}"
            f"{t.microseconds_per_step:>11.0f}{t.wall_per_simulated_second:>13.4g}{ratio}"
        )
    print(
        f"paper (n = 100, h = {PAPER_STEP:g} s): {paper_per_second:.1f} s per simulated second, "
        f"{1e6 * paper_per_step:.0f} us per step"
    )
    big = [t for t in timings if t.elements == 100][0]
    step_ratio = 1e6 * paper_per_step / big.microseconds_per_step
    print(
        f"per step at n = 100: paper / ours = {step_ratio:.1f}"
        f"; per simulated second: paper / ours = "
        f"{paper_per_second / big.wall_per_simulated_second:.0f} (our step h = {big.step:g} s is "
        "stable without torsion, the paper's included torsion)"
    )
    return timings
