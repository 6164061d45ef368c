"""Benchmarks that print their figures next to a baseline measured or quoted in the same run.

``cable-ocp bench`` times the RK4 step at n = 15 on ``paper_flat`` and n = 100 on ``end_force``,
interpreted (CasADi's SX virtual machine) and compiled to C, in the same run, and sets the wall time
per simulated second beside the paper's (5242 s for 100 s at n = 100, h = 2e-4 s).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from cable_ocp.compile import compiled as compile_function
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
    mode : str
        ``"interpreted"`` or ``"compiled"``.
    build_time : float, s
        Building the symbolic model and the step Function (and compiling it, if not cached).
    cache_hit : bool
        The compiled step came from the disk cache.
    microseconds_per_step : float, us
    wall_per_simulated_second : float, s/s
    """

    scene: str
    elements: int
    step: float
    mode: str
    build_time: float
    cache_hit: bool
    microseconds_per_step: float
    wall_per_simulated_second: float


def time_rk4(
    scene_path: Path, elements: int, steps: int, compiled: bool = False, repeats: int = 3
) -> StepTiming:
    """Time ``steps`` RK4 steps of a scene's model in one mapaccum (best of ``repeats``)."""
    scene = load_scene(scene_path, {"model.elements": elements})
    started = time.perf_counter()
    model = CableModel.from_scene(scene)
    step = scene.numerics.step
    function, hit = rk4_step(model, step), False
    if compiled:
        rhs, report = compile_function(model.rhs, repr(model.spec), derivatives=False, quiet=False)
        function, hit = rk4_step(model, step, rhs), report.cache_hit
    run = function.mapaccum(steps)
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
    mode = "compiled" if compiled else "interpreted"
    return StepTiming(scene.name, elements, step, mode, build, hit, 1e6 * per_step, per_step / step)


def rk4_report(models_dir: Path, quick: bool = False) -> list[StepTiming]:
    """Print the RK4 benchmark (interpreted and compiled, same run) and return its timings."""
    cases = [("paper_flat.toml", 15, 2000), ("end_force.toml", 100, 100 if quick else 300)]
    timings = []
    for name, n, steps in cases:
        for compiled in (False, True):
            timings.append(time_rk4(models_dir / name, n, steps, compiled))
    paper_per_second = PAPER_WALL_TIME / PAPER_SIMULATED
    paper_per_step = PAPER_WALL_TIME / (PAPER_SIMULATED / PAPER_STEP)
    print("RK4 step, best of 3 (build includes compiling when the cache misses)")
    print(f"{'scene':<12}{'n':>5}{'h [s]':>8}  {'mode':<12}{'build [s]':>10}{'cache':>7}"
          f"{'us/step':>10}{'ms/sim s':>10}{'vs interp.':>11}{'paper/ours':>11}")  # fmt: skip
    for t in timings:
        base = [b for b in timings if b.elements == t.elements and b.mode == "interpreted"][0]
        speedup = base.microseconds_per_step / t.microseconds_per_step
        ratio = paper_per_second / t.wall_per_simulated_second
        print(
            f"{t.scene:<12}{t.elements:>5}{t.step:>8.3g}  {t.mode:<12}{t.build_time:>10.1f}"
            f"{'hit' if t.cache_hit else '-':>7}{t.microseconds_per_step:>10.1f}"
            f"{1e3 * t.wall_per_simulated_second:>10.3f}{speedup:>10.1f}x"
            f"{ratio if t.elements == 100 else float('nan'):>11.0f}"
        )
    print(
        f"paper (n = 100, h = {PAPER_STEP:g} s, torsion): {paper_per_second:.1f} s per simulated "
        f"second, {1e6 * paper_per_step:.0f} us per step; our n = 100 runs without torsion at "
        "h = 0.01 s, stable and within 1e-3 m of h = 1e-3 s (studies/end_force_table)"
    )
    return timings


def hessian_report(models_dir: Path) -> None:
    """Print IPOPT with an exact and a limited-memory Hessian on ``small_tow`` (same run).

    The exact Hessian needs second derivatives, so it runs on the interpreted model; the
    limited-memory runs are timed interpreted and compiled.
    """
    from cable_ocp.ocp import IpoptSettings
    from cable_ocp.optimization import optimize

    scene = load_scene(models_dir / "small_tow.toml")
    cases = [("limited-memory", False), ("exact", False), ("limited-memory", True)]
    print("IPOPT Hessian on small_tow (n = 4, h = 0.25 s, 8 intervals), same run")
    print(f"{'hessian':<16}{'compiled':>9}{'iterations':>12}{'Omega [m]':>12}{'solve [s]':>11}"
          f"{'s/iteration':>13}{'build [s]':>11}")  # fmt: skip
    for hessian, compiled in cases:
        settings = IpoptSettings(step=0.25, intervals=8, hessian=hessian, compiled=compiled)
        r = optimize(scene, "ipopt", settings, quiet=True)
        print(
            f"{hessian:<16}{str(compiled):>9}{r.iterations:>12}{r.omega:>12.3e}"
            f"{r.solve_time:>11.1f}{r.solve_time / max(r.iterations, 1):>13.2f}"
            f"{r.build_time:>11.1f}"
        )
