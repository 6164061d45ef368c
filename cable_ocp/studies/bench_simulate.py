"""Benchmark of many simulations: end-to-end ``simulate`` against its integration, and a sweep.

``cable-ocp bench --only simulate`` prints three tables:

- the ``cable-ocp simulate`` command on ``end_force`` (n = 100), each run in a fresh process:
  compiled (the default, with a warm disk cache) against ``--interpreted`` (what the command
  ran before it compiled by default), in the same run, best of two each, taken in turns; both
  write the same files (checked: the same names, the same summary to 1e-9);
- ``simulate`` end to end (statics, integration with its bond checks, joints and tensions) with a
  warm cache, against the integration alone in the same run, and against ``simulate`` with the
  per-process caches emptied before each call (the model rebuilt, its library loaded from disk:
  what every call cost before the caches);
- a sweep over 20 currents in a fresh compile cache: the libraries compiled, the first run (which
  compiles) and the later ones, against the first run's compile time paid once per scene (what a
  library per scene, the numbers built in, would cost).
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from cable_ocp.drive.drive import Drive
from cable_ocp.model import parametric
from cable_ocp.model.cable import CableModel, cached_model
from cable_ocp.scene.schema import load_scene
from cable_ocp.simulation.integrate import integrate
from cable_ocp.simulation.run import simulate
from cable_ocp.simulation.statics import equilibrium

# (scene file, overrides): a model of n = 15 over 210 s and one of n = 100 over 20 s.
SIMULATE_CASES = (("paper_flat.toml", {}), ("end_force.toml", {}))
SWEEP_SCENE = "paper_flat.toml"
SWEEP_CURRENTS = np.linspace(0.0, 0.95, 20)  # m/s, across the tow (y)
REPEATS = 3
COMMAND_SCENE = "end_force.toml"
COMMAND_REPEATS = 2  # runs of each of the two commands, taken in turns (the best counts)
SUMMARY_TOLERANCE = 1e-9  # relative: compiled and interpreted give the same numbers to rounding
QUICK_COMMAND = ("--set", "numerics.duration=20")  # 20 s of the 100 s run


def _best(run: Callable[[], object], repeats: int = REPEATS) -> float:
    """Shortest wall time (s) of ``repeats`` calls."""
    times = []
    for _ in range(repeats):
        started = time.perf_counter()
        run()
        times.append(time.perf_counter() - started)
    return min(times)


def _forget_models() -> None:
    """Empty the per-process model caches (the disk cache of compiled libraries stays)."""
    cached_model.cache_clear()
    parametric.parametric_model.cache_clear()


def _time_case(scene) -> tuple[float, float, float]:
    """``simulate`` end to end, the integration alone and ``simulate`` with no model cache (s)."""
    numerics = scene.numerics
    simulate(scene, compiled=True)  # compile or load once: the cache is warm from here on
    model = CableModel.from_scene(scene)
    drive = Drive.from_scene(scene)
    x0 = equilibrium(model, drive, compiled=True).state
    integration = _best(
        lambda: integrate(
            model, x0, drive, numerics.duration, numerics.step, numerics.output_every,
            tolerance=numerics.constraint_tolerance, compiled=True,
        )
    )  # fmt: skip
    end_to_end = _best(lambda: simulate(scene, compiled=True))

    def uncached() -> None:
        _forget_models()
        simulate(scene, compiled=True)

    return end_to_end, integration, _best(uncached)


def simulate_report(models_dir: Path, quick: bool = False) -> list[tuple[str, float, float, float]]:
    """Print ``simulate`` end to end against the integration alone and against no model cache.

    Returns rows ``(scene, simulate, integrate, uncached)`` in seconds.
    """
    cases = SIMULATE_CASES[:1] if quick else SIMULATE_CASES
    print("simulate() end to end, compiled, warm disk cache (best of 3, same run)")
    print(f"{'scene':<18}{'n':>5}{'simulate [s]':>14}{'integrate [s]':>15}{'ratio':>8}"
          f"{'no model cache [s]':>20}{'ratio':>8}")  # fmt: skip
    rows = []
    for name, overrides in cases:
        scene = load_scene(models_dir / name, overrides)
        end_to_end, integration, rebuilt = _time_case(scene)
        rows.append((name, end_to_end, integration, rebuilt))
        print(
            f"{name:<18}{scene.model.elements:>5}{end_to_end:>14.3f}{integration:>15.3f}"
            f"{end_to_end / integration:>7.2f}x{rebuilt:>20.3f}{rebuilt / integration:>7.2f}x"
        )
    return rows


def sweep_report(models_dir: Path) -> tuple[int, float, list[float]]:
    """Print a sweep over 20 currents in a fresh compile cache: libraries and time per run.

    Returns ``(libraries compiled, first run in s, later runs in s)``.
    """
    scene = load_scene(models_dir / SWEEP_SCENE)
    previous = os.environ.get("CABLE_OCP_CACHE")
    with tempfile.TemporaryDirectory() as cache:
        os.environ["CABLE_OCP_CACHE"] = cache
        _forget_models()
        try:
            times = []
            for speed in SWEEP_CURRENTS:
                case = scene.updated({"environment.current": [0.0, float(speed), 0.0]})
                started = time.perf_counter()
                simulate(case, compiled=True)
                times.append(time.perf_counter() - started)
            libraries = len(list(Path(cache).glob("*.so")))
        finally:
            if previous is None:
                del os.environ["CABLE_OCP_CACHE"]
            else:
                os.environ["CABLE_OCP_CACHE"] = previous
            _forget_models()
    first, later = times[0], times[1:]
    per_scene = first + sum(later)
    per_scene_libraries = len(SWEEP_CURRENTS) * first
    print(f"\nSweep: {len(SWEEP_CURRENTS)} currents (0 to {SWEEP_CURRENTS[-1]:g} m/s across the "
          f"tow) on {scene.name}, n = {scene.model.elements}, fresh compile cache")  # fmt: skip
    print(f"libraries compiled: {libraries} (one set for the structure)")
    print(f"first run (compiles): {first:.2f} s; later runs: mean {np.mean(later):.3f} s, "
          f"max {max(later):.3f} s; whole sweep {per_scene:.2f} s")  # fmt: skip
    print(f"a library per scene would pay the first run's cost every time: about "
          f"{per_scene_libraries:.1f} s ({per_scene_libraries / per_scene:.1f}x)")  # fmt: skip
    return libraries, first, later


def _command_time(arguments: list[str]) -> tuple[float, tuple[list[str], dict]]:
    """``cable-ocp simulate ARGUMENTS --out TMP --quiet`` in a fresh process.

    Returns the wall time (s) and what it wrote: the file names and the summary.
    """
    with tempfile.TemporaryDirectory() as folder:
        out = Path(folder) / "out"
        command = [sys.executable, "-m", "cable_ocp.cli", "simulate", *arguments,
                   "--out", str(out), "--quiet"]  # fmt: skip
        started = time.perf_counter()
        subprocess.run(command, check=True, stdout=subprocess.DEVNULL)
        seconds = time.perf_counter() - started
        files = sorted(path.name for path in out.iterdir() if not path.name.startswith("."))
        return seconds, (files, json.loads((out / "summary.json").read_text()))


def _same_outputs(a: tuple[list[str], dict], b: tuple[list[str], dict]) -> bool:
    """The same files, and the same summary to :data:`SUMMARY_TOLERANCE` (relative)."""
    (files_a, summary_a), (files_b, summary_b) = a, b

    def numbers(summary):
        values = [summary[key] for key in sorted(summary) if key not in ("scene", "units")]
        return [
            float(v) for value in values for v in (value if isinstance(value, list) else [value])
        ]

    return (
        files_a == files_b
        and summary_a.keys() == summary_b.keys()
        and all(
            math.isclose(x, y, rel_tol=SUMMARY_TOLERANCE, abs_tol=SUMMARY_TOLERANCE)
            for x, y in zip(numbers(summary_a), numbers(summary_b), strict=True)
        )
    )


def command_report(models_dir: Path, quick: bool = False) -> tuple[float, float]:
    """Print ``cable-ocp simulate`` on end_force (n = 100), compiled against ``--interpreted``.

    Each run is a fresh process, figures and netCDF file included; the compiled library is built
    (or loaded) by an untimed first run. Each command runs :data:`COMMAND_REPEATS` times, the two
    in turns so that both see the same load; the best of each counts. Returns
    ``(compiled, interpreted)`` in seconds.

    Raises
    ------
    RuntimeError
        If the two commands did not write the same outputs.
    """
    arguments = [str(models_dir / COMMAND_SCENE), *(QUICK_COMMAND if quick else ())]
    _command_time(arguments)  # the library compiled or found in the disk cache
    compiled, interpreted = [], []
    for _ in range(COMMAND_REPEATS):
        compiled.append(_command_time(arguments))
        interpreted.append(_command_time([*arguments, "--interpreted"]))
    outputs = compiled[0][1]
    if not all(_same_outputs(outputs, run[1]) for run in compiled + interpreted):
        raise RuntimeError("cable-ocp simulate: compiled and --interpreted wrote different outputs")
    best_compiled, best_interpreted = (
        min(run[0] for run in runs) for runs in (compiled, interpreted)
    )
    span = "20 s" if quick else "100 s"
    print(f"cable-ocp simulate {COMMAND_SCENE} (n = 100, {span}): a fresh process each, the "
          f"library in the disk cache, best of {COMMAND_REPEATS} each in turns")  # fmt: skip
    print(f"{'compiled (default) [s]':>24}{'--interpreted [s]':>19}{'ratio':>8}")
    print(
        f"{best_compiled:>24.2f}{best_interpreted:>19.2f}{best_interpreted / best_compiled:>7.1f}x"
    )
    print(f"both wrote the same outputs: {', '.join(outputs[0])}\n")
    return best_compiled, best_interpreted


def report(models_dir: Path, quick: bool = False) -> None:
    """``cable-ocp bench --only simulate``: the three tables (the sweep also with ``quick``)."""
    command_report(models_dir, quick)
    simulate_report(models_dir, quick)
    sweep_report(models_dir)
