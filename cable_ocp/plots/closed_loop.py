"""Figures of a closed-loop run (matplotlib), by the rules of :mod:`cable_ocp.plots`.

Each function returns the figure; with ``path`` it is saved there and closed. Importing this module
selects no matplotlib backend.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from cable_ocp.control.closed_loop.result import MpcResult
from cable_ocp.plots import finish_figure, run_title, significant


def _run(result: MpcResult) -> str:
    return f"closed loop ({result.settings.get('solver', 'ipopt')})"


def clearance(
    result: MpcResult, path: str | Path | None = None, scene_name: str | None = None
) -> Figure:
    """Clearance error e(t) (eq. 39) of the closed loop against the reference runs.

    The upper panel shows every run; the lower one zooms on the runs within 10 times the closed
    loop's largest error (the locked winch is metres off). ``scene_name`` is named in the title
    (an :class:`MpcResult` does not know its scene); so in every figure of this module.
    """
    fig, axes = plt.subplots(2, 1, figsize=(10, 6.8), sharex=True)
    runs = [(f"{_run(result)} (Omega = {significant(result.omega)} m)", result.clearance_error)]
    runs += [
        (f"{name} (Omega = {significant(result.reference_omegas[name])} m)", error)
        for name, error in result.references.items()
    ]
    scale = 10 * np.max(np.abs(result.clearance_error))
    for index, (label, error) in enumerate(runs):
        style = {
            "lw": 1.6 if index == 0 else 1.0,
            "zorder": 3 if index == 0 else 2,
            "color": f"C{index}",
        }
        axes[0].plot(result.time, error, label=label, **style)
        if np.max(np.abs(error)) <= scale:
            axes[1].plot(result.time, error, label=label, **style)
    axes[0].set_ylabel("e [m]")
    axes[0].set_title(run_title("clearance error of the end E, e = z_E - z_E(0) - z_hill",
                                [scene_name], [_run(result), *result.references]))  # fmt: skip
    axes[0].legend(fontsize=8)
    axes[1].set_ylabel("e [m] (zoom)")
    axes[1].set_xlabel("t [s]")
    axes[1].legend(fontsize=8)
    for ax in axes:
        ax.grid(alpha=0.3)
    return finish_figure(fig, path)


def _failed(result: MpcResult) -> np.ndarray:
    """Which samples' solves failed (the loop names each failure by its sample time)."""
    failed_at = {failure.split(" s:", 1)[0] for failure in result.failures}
    return np.array([f"t = {t:g}" in failed_at for t in result.sample_times], dtype=bool)


def solve_times(
    result: MpcResult, path: str | Path | None = None, scene_name: str | None = None
) -> Figure:
    """Wall time and iterations of each solve, against the sample time (real time)."""
    fig, ax = plt.subplots(figsize=(10, 4.2))
    times = result.sample_times
    sample = times[1] - times[0] if times.size > 1 else result.time[-1] - result.time[0]
    ax.bar(
        result.sample_times, 1e3 * result.solve_times, width=0.8 * sample, align="edge",
        label="solve",
    )  # fmt: skip
    ax.axhline(1e3 * sample, color="k", ls="--", lw=1, label=f"sample = {sample:g} s (real time)")
    failed = _failed(result)
    if failed.any():
        ax.plot(result.sample_times[failed], 1e3 * result.solve_times[failed], "rx", label="failed")
    ax.set_yscale("log")
    ax.set_ylim(0.5 * 1e3 * result.solve_times.min(), 2e3 * max(sample, result.worst_solve_time))
    ax.set_xlabel("t [s]")
    ax.set_ylabel("wall time [ms]")
    ax.set_title(
        f"{run_title('solve time per sample', [scene_name], [_run(result)])}, median "
        f"{significant(1e3 * np.median(result.solve_times))} ms, worst "
        f"{significant(1e3 * result.worst_solve_time)} ms, real-time factor "
        f"{significant(result.real_time_factor)}"
    )
    twin = ax.twinx()
    twin.plot(result.sample_times + 0.4 * sample, result.iterations, "C1.", label="iterations")
    twin.set_ylabel("iterations per solve [count]")
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
        median = 1e3 * np.median(result.solve_times)
        ax.plot(
            result.sample_times, 1e3 * result.solve_times, ".-", lw=0.8, ms=3,
            label=f"{label}: median {significant(median)} ms, Omega {significant(result.omega)} m",
        )  # fmt: skip
    ax.set_yscale("log")
    ax.set_xlabel("t [s]")
    ax.set_ylabel("solve wall time [ms]")
    ax.set_title(run_title("solve time per sample", [scene_name], list(results)))
    ax.legend(fontsize=8)
    return finish_figure(fig, path)


def winch_angle(
    result: MpcResult, path: str | Path | None = None, scene_name: str | None = None
) -> Figure:
    """Winch angle applied (with the heave feedback) and planned, with the bounds (dotted)."""
    fig, ax = plt.subplots(figsize=(10, 4.2))
    ax.plot(result.time, result.winch_angle, lw=0.9, label="applied")
    ax.plot(result.time, result.planned_angle, lw=1.6, label="planned (controller)")
    low, high = result.angle_range
    text = f"winch range phi_min = {low:g} rad, phi_max = {high:g} rad"
    for k, bound in enumerate(result.angle_range):
        ax.axhline(bound, color="k", ls=":", lw=1, label=text if k == 0 else None)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("winch angle phi [rad]")
    ax.set_title(run_title("winch angle", [scene_name], [_run(result)]))
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    return finish_figure(fig, path)
