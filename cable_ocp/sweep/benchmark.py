"""``sweep_benchmark``: the same OCP sweep on 1 and on 2 Dask workers, timed in one run."""

from __future__ import annotations

import os
import tempfile
import time
from pathlib import Path

import numpy as np

from cable_ocp.scene.bundled import models_dir
from cable_ocp.sweep import execute
from cable_ocp.sweep.runner import run_sweep
from cable_ocp.sweep.spec import load_sweep

SWEEP = """
scene = "{scene}"
task = "{task}"
{optimizer}
[set]
"numerics.duration" = 20.0
[grid]
"top.tow.surge_speed" = {speeds}
"""
OPTIMIZER = 'method = "shooting"\n[optimizer]\nelements = 4\nstep = 0.25\nintervals = 8'


def _load() -> str:
    try:
        return " ".join(f"{v:.2f}" for v in os.getloadavg())
    except OSError:
        return "unknown"


def sweep_benchmark(
    cases: int = 16, task: str = "optimize", worker_counts: tuple[int, ...] = (1, 2)
) -> dict[int, float]:
    """Run one sweep of ``small_tow`` (20 s, ``cases`` surge speeds) on 1 and 2 workers; print.

    Each OCP case is IPOPT on the n = 4 model at h = 0.25 s with 8 shooting intervals (about
    10 s on one core). The compiled model is built once, untimed, before the timed runs, so
    every run finds it in the cache. Wall times include starting the LocalCluster (processes).
    Measured on the 2-core machine with nothing else running (load 0.06): 16 OCP cases in
    92.4 s on 1 worker, 50.6 s on 2, a speed-up of 1.83x (with another job on one core: 0.69x).

    Parameters
    ----------
    cases : int
        Surge speeds from 0.6 to 1.4 m/s.
    task : str
        ``"optimize"`` or ``"simulate"``.
    worker_counts : tuple of int
        Worker counts timed, in this order.

    Returns
    -------
    dict
        Wall time (s) per worker count.
    """
    speeds = [round(float(v), 4) for v in np.linspace(0.6, 1.4, cases)]
    text = SWEEP.format(
        scene=models_dir() / "small_tow.toml",
        task=task,
        optimizer=OPTIMIZER if task == "optimize" else "",
        speeds=speeds,
    )
    walls: dict[int, float] = {}
    with tempfile.TemporaryDirectory(prefix="sweep_bench_") as scratch:
        path = Path(scratch) / "bench.toml"
        path.write_text(text)
        spec = load_sweep(path)
        warm = execute.run_case(spec.cases[0].scene, spec.task, spec.method, spec.settings)
        print(f"sweep benchmark: {cases} {task} cases of small_tow (20 s, surge 0.6..1.4 m/s); "
              f"one case in this process (cache warm-up): {warm['wall_time']:.1f} s; "
              f"load average before: {_load()}")  # fmt: skip
        print(f"{'workers':>8}{'wall [s]':>10}{'case sum [s]':>14}{'ok':>5}{'speed-up':>10}")
        for count in worker_counts:
            started = time.perf_counter()
            report = run_sweep(spec, Path(scratch) / f"w{count}", workers=count, quiet=True)
            walls[count] = time.perf_counter() - started
            ds = report.dataset
            ok = int((ds["status"] == "ok").sum())
            speedup = walls[worker_counts[0]] / walls[count]
            print(f"{count:>8}{walls[count]:>10.1f}{float(ds['wall_time'].sum()):>14.1f}"
                  f"{ok:>5}{speedup:>9.2f}x")  # fmt: skip
    print(f"load average after: {_load()} (1, 5, 15 min; other work on the machine slows it)")
    return walls
