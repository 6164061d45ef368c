"""Benchmarks that print their figures next to a baseline measured or quoted in the same run.

``cable-ocp bench`` has these parts, each printing a table:

- ``rk4``: the simulation loop (:func:`cable_ocp.simulation.integrate.integrate`, bond checks
  included) at n = 15 on ``paper_flat`` (winch locked) and n = 100 on ``end_force``,
  interpreted (CasADi's SX virtual machine) and compiled to C, at the scene's step and at a larger
  one, with the error of each step against a run at a quarter of it, so that a faster step is
  seen to be accurate; the paper's 52 s per simulated second (n = 100) as a ratio; compile and
  cache-load times.
- ``moordyn``: the same cable and tow in MoorDyn at its largest stable step (optional extra).
- ``ocp``: IPOPT (single shooting) against the paper's Nelder-Mead on ``paper_flat``:
  seconds per iteration or evaluation, total, and the verified Omega.
- ``ocp-speed``: the default ``optimize`` of ``paper_hill`` end to end, each run in a fresh
  process: cold (an empty compile cache) and warm, split into build / compile / solve /
  verification, for the Gauss-Newton solver (the default) against IPOPT with its limited-memory
  Hessian (the default before) in the same run.
- ``mpc`` (:mod:`cable_ocp.studies.bench_mpc`): the closed loop's solve times and Omega.

``cable-ocp bench --hessian`` compares IPOPT's exact and limited-memory Hessians.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from cable_ocp.control.ipopt import IpoptSettings
from cable_ocp.control.optimization import OcpResult, optimize
from cable_ocp.control.settings import GridSettings, ModelSettings, TranscriptionSettings
from cable_ocp.control.shooting import control_of
from cable_ocp.control.solvers import DEFAULT_SOLVER, SOLVERS
from cable_ocp.drive.drive import Drive
from cable_ocp.model.cable import CableModel
from cable_ocp.scene.schema import load_scene
from cable_ocp.simulation.integrate import (
    integrate,
    stage_inputs,
    step_compile_report,
    step_function,
)
from cable_ocp.simulation.statics import equilibrium

PAPER_WALL_TIME = 5242.0  # s, for 100 s simulated at n = 100 (paper §4.2)
PAPER_SIMULATED = 100.0  # s
PAPER_STEP = 2e-4  # s
# (scene file, n, steps): a small step and the largest one within 1e-5 m of h/4 (inside the
# stability limit, notebooks/studies/stability).
RK4_CASES = (("paper_flat.toml", 15, (0.05, 0.2)), ("end_force.toml", 100, (0.01, 0.025)))
# The interpreted baseline runs this much simulated time (s) per case: it is 10-20x slower.
INTERPRETED_DURATION = {15: 10.0, 100: 2.0}
ACCURACY_REFINEMENT = 4  # each step's error is measured against a run at step / 4


@dataclass(frozen=True)
class StepTiming:
    """Cost and accuracy of the RK4 simulation loop of one model at one step.

    Attributes
    ----------
    scene : str
        File name of the scene in ``models/``.
    elements : int
        Number of elements n of the model.
    step : float, s
        RK4 step h.
    mode : str
        ``"interpreted"`` or ``"compiled"``.
    build_time : float, s
        Building the model and its step (compiling it when the cache misses).
    compile_time : float, s
        Of ``build_time``, compiling C (0 on a cache hit or interpreted).
    reload_time : float, s
        Building a fresh model's step again: the cache hit of a second run (compiled only).
    cache_hit : bool
        The first build already found the compiled step in the cache.
    simulated : float, s
        Simulated time of the timed run.
    microseconds_per_step : float, us
        Kernel only: one call of the step map over the whole run.
    wall_per_simulated_second : float, s/s
        The whole simulation loop (:func:`integrate`: inputs, steps, bond and blow-up checks).
    end_error : float, m
        Largest end-position difference against the same run at ``step / 4`` (NaN when not
        measured: interpreted runs give the same numbers as compiled ones).
    """

    scene: str
    elements: int
    step: float
    mode: str
    build_time: float
    compile_time: float
    reload_time: float
    cache_hit: bool
    simulated: float
    microseconds_per_step: float
    wall_per_simulated_second: float
    end_error: float


def _best_time(run, repeats: int) -> tuple[float, object]:
    """Best wall time (s) of ``repeats`` calls, and what the last call returned."""
    best, result = np.inf, None
    for _ in range(repeats):
        started = time.perf_counter()
        result = run()
        best = min(best, time.perf_counter() - started)
    return best, result


def _build(scene, compiled: bool, step: float):
    started = time.perf_counter()
    model = CableModel.from_scene(scene)
    step_function(model, step, compiled)
    elapsed = time.perf_counter() - started
    report = step_compile_report(model, step) if compiled else None
    return model, elapsed, report


def time_simulation(
    scene_path: Path, elements: int, step: float, compiled: bool, repeats: int = 3
) -> StepTiming:
    """Time the RK4 loop of a scene's model (best of ``repeats``) and measure its accuracy.

    Parameters
    ----------
    scene_path : Path
        Scene file to load.
    elements : int
        Number of elements n, set on the scene.
    step : float, s
        RK4 step h, set on the scene.
    compiled : bool
        Compile the step to C; otherwise CasADi's SX virtual machine runs it.
    repeats : int
        How many timed runs, of which the best counts.
    """
    scene = load_scene(scene_path, {"model.elements": elements, "numerics.step": step})
    duration = scene.numerics.duration if compiled else INTERPRETED_DURATION[elements]
    model, build, report = _build(scene, compiled, step)
    reload = _build(scene, compiled, step)[1] if compiled else 0.0
    drive = Drive.from_scene(scene)
    x0 = equilibrium(model, drive).state
    count = round(duration / step)
    kernel = step_function(model, step, compiled).mapaccum(count)
    inputs = stage_inputs(drive, np.arange(count) * step, step)
    per_step = _best_time(lambda: kernel(x0, inputs), repeats)[0] / count

    tolerance = scene.numerics.constraint_tolerance

    def loop():
        return integrate(model, x0, drive, duration, step, tolerance=tolerance, compiled=compiled)

    wall, coarse = _best_time(loop, repeats)
    error = float("nan")
    if compiled:
        fine = integrate(
            model,
            x0,
            drive,
            duration,
            step / ACCURACY_REFINEMENT,
            output_every=ACCURACY_REFINEMENT,
            tolerance=np.inf,
            compiled=True,
        )
        error = float(np.max(np.linalg.norm(coarse.states[:, :3] - fine.states[:, :3], axis=1)))
    return StepTiming(
        scene=scene.name,
        elements=elements,
        step=step,
        mode="compiled" if compiled else "interpreted",
        build_time=build,
        compile_time=report.compile_time if report else 0.0,
        reload_time=reload,
        cache_hit=bool(report and report.cache_hit),
        simulated=duration,
        microseconds_per_step=1e6 * per_step,
        wall_per_simulated_second=wall / duration,
        end_error=error,
    )


def rk4_report(models_dir: Path, quick: bool = False) -> list[StepTiming]:
    """Print the RK4 benchmark (interpreted and compiled, same run) and return its timings.

    ``quick`` times the small steps only.
    """
    timings = []
    for name, n, steps in RK4_CASES:
        for step in steps[:1] if quick else steps:
            for compiled in (False, True):
                timings.append(time_simulation(models_dir / name, n, step, compiled))
    paper_per_second = PAPER_WALL_TIME / PAPER_SIMULATED
    print("RK4 simulation loop (best of 3); interpreted and compiled in the same run")
    print(f"{'scene':<11}{'n':>4}{'h [s]':>7}  {'mode':<12}{'build [s]':>10}{'compile':>8}"
          f"{'reload':>7}{'us/step':>9}{'ms/sim s':>10}{'speed-up':>9}{'paper/ours':>11}"
          f"{'err vs h/4 [m]':>15}")  # fmt: skip
    for t in timings:
        base = [
            b
            for b in timings
            if (b.elements, b.step, b.mode) == (t.elements, t.step, "interpreted")
        ][0]
        speedup = base.wall_per_simulated_second / t.wall_per_simulated_second
        ratio = paper_per_second / t.wall_per_simulated_second if t.elements == 100 else np.nan
        print(
            f"{t.scene:<11}{t.elements:>4}{t.step:>7.3g}  {t.mode:<12}{t.build_time:>10.1f}"
            f"{t.compile_time:>8.1f}{t.reload_time:>7.2f}{t.microseconds_per_step:>9.1f}"
            f"{1e3 * t.wall_per_simulated_second:>10.3f}{speedup:>8.1f}x{ratio:>11.0f}"
            f"{t.end_error:>15.2e}"
        )
    print(
        f"paper (n = 100, h = {PAPER_STEP:g} s, torsion): {paper_per_second:.1f} s per simulated "
        "second. Interpreted runs simulate "
        + ", ".join(f"{v:g} s at n = {k}" for k, v in INTERPRETED_DURATION.items())
        + "; compiled runs the whole scene. 'reload' builds a fresh model whose compiled step "
        "comes from the disk cache."
    )
    return timings


def ocp_report(models_dir: Path, quick: bool = False) -> list[tuple[str, OcpResult]]:
    """Print Gauss-Newton against Nelder-Mead on ``paper_flat`` (``small_tow`` when ``quick``).

    Returns the rows as ``(label, result)``.
    """
    if quick:
        scene = load_scene(models_dir / "small_tow.toml")
        cases = [
            (None, "Gauss-Newton, Hermite", QUICK_OCP_SETTINGS),
            ("nelder-mead", "Nelder-Mead, knots", {"model": ModelSettings(step=0.25)}),
        ]
    else:
        scene = load_scene(models_dir / "paper_flat.toml")
        spline = {"model": ModelSettings(3, 0.5), "grid": GridSettings(control="spline")}
        cases = [
            (None, "Gauss-Newton, Hermite", {}),
            (None, "Gauss-Newton, 14-knot spline", spline),
            ("nelder-mead", "Nelder-Mead, 14 knots", {}),
        ]
    rows = [(label, optimize(scene, solver, quiet=True, **parts)) for solver, label, parts in cases]
    print(f"Winch optimisation on {scene.name} (Omega verified on the scene's n = "
          f"{scene.model.elements} model), same run")  # fmt: skip
    print(f"{'method':<24}{'Omega [m]':>11}{'success':>9}{'iter.':>7}{'evals':>7}{'solve [s]':>11}"
          f"{'s/iter.':>9}{'s/eval':>8}{'total [s]':>11}{'vs GN':>10}")  # fmt: skip
    baseline = rows[0][1].wall_time
    for label, r in rows:
        print(
            f"{label:<24}{r.omega:>11.3e}{str(r.success):>9}{r.iterations:>7}"
            f"{r.evaluations:>7}{r.solve_time:>11.1f}"
            f"{r.solve_time / max(r.iterations, 1):>9.2f}"
            f"{r.solve_time / max(r.evaluations, 1):>8.3f}{r.wall_time:>11.1f}"
            f"{r.wall_time / baseline:>9.2f}x"
        )
    for label, r in rows:
        if not r.success:
            print(f"{label}: not converged: {r.status}")
    return rows


def hessian_report(models_dir: Path) -> None:
    """Print IPOPT with an exact and a limited-memory Hessian on ``small_tow`` (same run).

    The exact Hessian needs second derivatives, so it runs on the interpreted model; the
    limited-memory runs are timed interpreted and compiled.
    """
    scene = load_scene(models_dir / "small_tow.toml")
    cases = [("limited-memory", False), ("exact", False), ("limited-memory", True)]
    print("IPOPT Hessian on small_tow (n = 4, h = 0.25 s, 8 intervals), same run")
    print(f"{'hessian':<16}{'compiled':>9}{'iterations':>12}{'Omega [m]':>12}{'solve [s]':>11}"
          f"{'s/iteration':>13}{'build [s]':>11}")  # fmt: skip
    for hessian, compiled in cases:
        r = optimize(
            scene,
            "ipopt",
            IpoptSettings(hessian=hessian),
            transcription=TranscriptionSettings(compiled=compiled),
            quiet=True,
            **QUICK_OCP_SETTINGS,
        )
        print(
            f"{hessian:<16}{str(compiled):>9}{r.iterations:>12}{r.omega:>12.3e}"
            f"{r.solve_time:>11.1f}{r.solve_time / max(r.iterations, 1):>13.2f}"
            f"{r.build_time:>11.1f}"
        )


# The open-loop goals of the default optimize of paper_hill (wall time of optimize(), s).
WARM_GOAL, COLD_GOAL = 1.5, 10.0
# The quick ocp-speed runs: small_tow as in the quick ocp part (n = 4, h = 0.25 s, 8 intervals).
QUICK_OCP_SETTINGS = {"model": ModelSettings(step=0.25), "grid": GridSettings(intervals=8)}


def ocp_speed_case(scene_path: str, solver: str, quick: bool) -> dict:
    """One ``optimize`` of a scene timed in this process, as a dict of figures.

    The scene's default settings with ``solver`` (``"gauss-newton"``: the default; ``"ipopt"``:
    IPOPT with its limited-memory Hessian, the default before); ``quick``:
    :data:`QUICK_OCP_SETTINGS`. Times in s, Omega in m.
    """
    from cable_ocp.drive.bounds import violation

    scene = load_scene(scene_path)
    parts = QUICK_OCP_SETTINGS if quick else {"model": ModelSettings(3, 0.5)}
    started = time.perf_counter()
    result = optimize(scene, solver, quiet=True, **parts)
    wall = time.perf_counter() - started
    control = control_of(result.control, result.scene.numerics.duration, result.nodes)
    return {
        "wall": wall,
        "build": result.build_time - result.compile_time,
        "compile": result.compile_time,
        "solve": result.solve_time,
        "verification": result.verification_time,
        "iterations": result.iterations,
        "solves": len(result.refinements),
        "omega": result.omega,
        "success": result.success,
        "bounds_held": violation(scene, control, result.parameters) is None,
    }


def _ocp_speed_process(scene_path: Path, solver: str, quick: bool, cache: Path) -> dict:
    """:func:`ocp_speed_case` in a fresh Python process with ``$CABLE_OCP_CACHE = cache``.

    ``process`` is the process's whole wall time (s): interpreter, imports and the run.
    """
    code = (
        "import json, sys; from cable_ocp.studies.bench import ocp_speed_case; "
        "print(json.dumps(ocp_speed_case(sys.argv[1], sys.argv[2], sys.argv[3] == 'quick')))"
    )
    command = [sys.executable, "-c", code, str(scene_path), solver, "quick" if quick else "full"]
    env = {**os.environ, "CABLE_OCP_CACHE": str(cache)}
    started = time.perf_counter()
    run = subprocess.run(command, env=env, capture_output=True, text=True)
    elapsed = time.perf_counter() - started
    if run.returncode != 0:
        raise RuntimeError(f"the timed optimize process failed:\n{run.stderr.strip()[-2000:]}")
    return {**json.loads(run.stdout.strip().splitlines()[-1]), "process": elapsed}


def ocp_speed_report(models_dir: Path, quick: bool = False) -> list[tuple[str, dict]]:
    """Print the default ``optimize`` of ``paper_hill`` cold and warm against IPOPT's.

    Every run is a fresh process; each cold one starts from an empty compile cache (a temporary
    folder per solver), the warm one after it reuses what it compiled. ``quick``: ``small_tow``
    with :data:`QUICK_OCP_SETTINGS`. Returns the rows as ``(label, figures)``.
    """
    name = "small_tow" if quick else "paper_hill"
    scene_path = models_dir / f"{name}.toml"
    # The default solver, and IPOPT with its limited-memory Hessian (the default before).
    solvers = (
        (SOLVERS[DEFAULT_SOLVER].label, DEFAULT_SOLVER),
        (SOLVERS["ipopt"].label + " L-BFGS", "ipopt"),
    )
    rows = []
    for label, solver in solvers:
        with tempfile.TemporaryDirectory(prefix="cable_ocp_bench_") as cache:
            rows += [
                (f"{label}, {start}", _ocp_speed_process(scene_path, solver, quick, Path(cache)))
                for start in ("cold", "warm")
            ]
    print(f"optimize({name}) end to end, default IPOPT settings, each run a fresh process; "
          "cold: empty compile cache; same run")  # fmt: skip
    print(f"{'case':<26}{'process':>8}{'wall':>7}{'build':>7}{'compile':>8}{'solve':>7}"
          f"{'verify':>7}{'other':>7}{'iter.':>6}{'solves':>7}{'Omega [m]':>11}{'success':>8}"
          f"{'bounds':>7}{'vs base':>8}")  # fmt: skip
    baselines = {"cold": rows[2][1]["wall"], "warm": rows[3][1]["wall"]}
    for label, r in rows:
        baseline = baselines[label.rsplit(" ", 1)[1]]
        other = r["wall"] - r["build"] - r["compile"] - r["solve"] - r["verification"]
        print(
            f"{label:<26}{r['process']:>8.1f}{r['wall']:>7.1f}{r['build']:>7.1f}"
            f"{r['compile']:>8.1f}{r['solve']:>7.1f}{r['verification']:>7.1f}{other:>7.1f}"
            f"{r['iterations']:>6}{r['solves']:>7}{r['omega']:>11.3e}{str(r['success']):>8}"
            f"{'held' if r['bounds_held'] else 'BROKEN':>7}{baseline / r['wall']:>7.1f}x"
        )
    print(
        "times in s; 'process' includes starting Python and the imports, 'wall' is optimize() "
        "alone; 'compile': how long the solve waited for the C compiler (the libraries start "
        "compiling in the background, side by side, when the problem is stated); 'verify': the "
        "full-model runs (model correction's at a coarser step, the reported profile's at the "
        "scene's); 'other': stating the problem (cold: generating the C and waiting for the "
        "optimisation model's library) and the first guess; 'vs base': IPOPT's wall "
        "(the default before, as cold or as warm) over the row's."
    )
    if not quick:
        cold, warm = rows[0][1], rows[1][1]
        same = abs(warm["omega"] - rows[3][1]["omega"]) <= 1e-3 * rows[3][1]["omega"]
        print(
            f"goals (Gauss-Newton, the default): warm <= {WARM_GOAL:g} s: {warm['wall']:.2f} s "
            f"({'met' if warm['wall'] <= WARM_GOAL else 'NOT met'}); cold <= {COLD_GOAL:g} s: "
            f"{cold['wall']:.2f} s ({'met' if cold['wall'] <= COLD_GOAL else 'NOT met'}); "
            f"verified Omega {warm['omega']:.4e} m against the baseline's "
            f"{rows[3][1]['omega']:.4e} m ({'the same' if same else 'DIFFERENT'} to 0.1 %)"
        )
    return rows
