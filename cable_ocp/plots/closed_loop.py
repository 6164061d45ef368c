"""Figures of a closed loop's solves (matplotlib), by the rules of :mod:`cable_ocp.plots`.

Its run is drawn by the functions of :mod:`cable_ocp.plots`, as an open loop's is
(``plots.clearance(result)``, ``plots.winch_angle(result)``); the solves are the closed loop's
own. Each function returns the figure; with ``path`` it is saved there and closed. Importing this
module selects no matplotlib backend.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator

from cable_ocp.control.closed_loop.result import MpcResult
from cable_ocp.plots import finish_figure, result_label, run_title, significant


def _failed(result: MpcResult) -> np.ndarray:
    """Which samples' solves failed (the loop names each failure by its sample time)."""
    failed_at = {failure.split(" s:", 1)[0] for failure in result.failures}
    return np.array([f"t = {t:g}" in failed_at for t in result.solves.sample_time], dtype=bool)


def solve_times(
    result: MpcResult, path: str | Path | None = None, scene_name: str | None = None
) -> Figure:
    """Wall time and iterations of each solve, against the sample time (real time).

    ``scene_name`` names the scene in the title (default: the plant's).
    """
    fig, ax = plt.subplots(figsize=(10, 4.2))
    solves = result.solves
    scene_name = scene_name or result.trajectory.scene_name
    times = solves.sample_time
    sample = times[1] - times[0] if times.size > 1 else result.time[-1] - result.time[0]
    wall = 1e3 * solves.solve_time
    ax.bar(times, wall, width=0.8 * sample, align="edge", label="solve")
    ax.axhline(1e3 * sample, color="k", ls="--", lw=1, label=f"sample = {sample:g} s (real time)")
    failed = _failed(result)
    if failed.any():
        ax.plot(solves.sample_time[failed], wall[failed], "rx", label="failed")
    ax.set_yscale("log")
    ax.set_ylim(0.5 * wall.min(), 2e3 * max(sample, result.worst_solve_time))
    ax.set_xlabel("t [s]")
    ax.set_ylabel("wall time [ms]")
    ax.set_title(
        f"{run_title('solve time per sample', [scene_name], [result_label(result)])}, median "
        f"{significant(np.median(wall))} ms, worst "
        f"{significant(1e3 * result.worst_solve_time)} ms, real-time factor "
        f"{significant(result.real_time_factor)}"
    )
    twin = ax.twinx()
    twin.plot(solves.sample_time + 0.4 * sample, solves.iterations, "C1.", label="iterations")
    twin.set_ylabel("iterations per solve [count]")
    # A count from 0, in whole ticks (one iteration a solve read 0.96-1.04).
    twin.set_ylim(0, 1.15 * max(solves.iterations.max(initial=1), 1) + 0.5)
    twin.yaxis.set_major_locator(MaxNLocator(integer=True))
    lines, labels = ax.get_legend_handles_labels()
    more, more_labels = twin.get_legend_handles_labels()
    ax.legend(lines + more, labels + more_labels, fontsize=8, loc="upper right")
    return finish_figure(fig, path)


def solve_time_comparison(
    results: dict[str, MpcResult], path: str | Path | None = None, scene_name: str | None = None
) -> Figure:
    """Solve time per sample of several closed loops on one log axis (the MPC benchmark)."""
    fig, ax = plt.subplots(figsize=(10, 4))
    for label, result in results.items():
        wall = 1e3 * result.solves.solve_time
        ax.plot(
            result.solves.sample_time, wall, ".-", lw=0.8, ms=3,
            label=f"{label}: median {significant(np.median(wall))} ms, Omega "
            f"{significant(result.omega)} m",
        )  # fmt: skip
    ax.set_yscale("log")
    ax.set_xlabel("t [s]")
    ax.set_ylabel("solve wall time [ms]")
    ax.set_title(run_title("solve time per sample", [scene_name], list(results)))
    ax.legend(fontsize=8)
    return finish_figure(fig, path)
