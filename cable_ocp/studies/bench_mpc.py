"""The closed loop's benchmark (``cable-ocp bench --only mpc``): solve times and Omega, same run.

The README's heave case (``paper_hill`` with a 1 m, 8 s heave) under four controllers on one plant:
the earlier path (IPOPT with a limited-memory Hessian on the multiple-shooting NLP, re-solved every
5 s, its heave margin 1), the real-time iteration on those same settings (one Gauss-Newton step per
solve: the speed-up alone), the default (the real-time iteration re-solved every 1 s), and the
default with its plan's first interval one sample long (``MpcSettings.first_interval``, move
blocking). Printed: median and worst solve, real-time factor of the whole loop (simulated time over
the loop's wall time, plant included), Omega and the ratios against the baseline. The controller's
libraries are compiled before the timed runs (warm cache).
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from cable_ocp.control.closed_loop.loop import mpc
from cable_ocp.control.closed_loop.references import ReferenceRuns, reference_runs
from cable_ocp.control.closed_loop.result import MpcResult
from cable_ocp.control.closed_loop.settings import MpcSettings
from cable_ocp.control.ipopt import IpoptSettings
from cable_ocp.control.settings import ModelSettings
from cable_ocp.scene.schema import load_scene

HEAVE = {"top.heave.amplitude": 1.0, "top.heave.period": 8.0}
# The closed loop as it was before the real-time iteration (its defaults then).
BASELINE = MpcSettings(
    sample=5.0,
    interval=5.0,
    model=ModelSettings(step=1.0),
    solver="ipopt",
    solver_settings=IpoptSettings(max_iter=100, tolerance=1e-6),
    heave_margin=1.0,
    limiter_band=0.2,
)
CASES = (
    ("IPOPT L-BFGS, 5 s sample (baseline)", BASELINE),
    (
        "Gauss-Newton RTI, 5 s sample",
        replace(BASELINE, solver="gauss-newton", solver_settings=None),
    ),
    ("Gauss-Newton RTI, 1 s sample (default)", MpcSettings()),
    ("RTI, 1 s sample, first plan interval 1 s", MpcSettings(first_interval=1.0)),
)
QUICK_DURATION = 40.0  # s of the scene with --quick


def run_cases(
    models_dir: Path, quick: bool = False
) -> tuple[dict[str, MpcResult], dict[str, ReferenceRuns]]:
    """Each case of :data:`CASES` on the heave case, after one untimed warm-up run of each.

    With each, its locked-winch reference run on its plant.
    """
    changes = {**HEAVE, **({"numerics.duration": QUICK_DURATION} if quick else {})}
    scene = load_scene(models_dir / "paper_hill.toml", changes)
    warm = scene.updated({"numerics.duration": 20.0})
    for _, settings in CASES:  # compile (or load) the controller's and the plant's libraries
        mpc(warm, settings, quiet=True)
    runs = {label: mpc(scene, settings, quiet=True) for label, settings in CASES}
    return runs, {label: reference_runs(scene, run) for label, run in runs.items()}


def report(models_dir: Path, quick: bool = False) -> dict[str, MpcResult]:
    """Print the benchmark's table (see the module docstring) and return the runs by label."""
    results, references = run_cases(models_dir, quick)
    baseline = results[CASES[0][0]]
    base_median = float(np.median(baseline.solves.solve_time))
    duration = baseline.time[-1]
    print(f"mpc on paper_hill with a 1 m, 8 s heave ({duration:g} s), 20 s horizon, same plant, "
          "same run; libraries compiled beforehand")  # fmt: skip
    print(f"{'case':<40}{'solves':>7}{'median':>10}{'worst':>10}{'RTF':>7}{'Omega [m]':>11}"
          f"{'locked [m]':>11}{'success':>8}{'median vs base':>15}")  # fmt: skip
    for label, r in results.items():
        median = float(np.median(r.solves.solve_time))
        locked = references[label].omegas.get("locked", float("nan"))
        print(
            f"{label:<40}{r.solves.sample_time.size:>7}{1e3 * median:>8.1f}ms"
            f"{1e3 * r.worst_solve_time:>8.1f}ms{r.real_time_factor:>7.1f}{r.omega:>11.4g}"
            f"{locked:>11.4g}{str(r.success):>8}"
            f"{base_median / median:>14.0f}x"
        )
    print(
        "median/worst: wall time of one solve; RTF: simulated time over the loop's wall time "
        "(plant, estimator and solves); goals: median <= 20 ms, worst <= 100 ms, RTF >= 50 at "
        "a 1 s sample, Omega no worse than the baseline's"
    )
    return results
