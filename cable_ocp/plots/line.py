"""A run of a line paid out by elements: line out, element count, top element and tension."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
from matplotlib.figure import Figure

from cable_ocp.plots.figure import finish_figure
from cable_ocp.simulation.line_trajectory import LineTrajectory


def line_run(trajectory, path: str | Path | None = None) -> Figure:
    """Line out and ``n``, the top element within its range, the top tension, the end's depth.

    Parameters
    ----------
    trajectory : LineTrajectory
        A run of a scene with ``[winch.line]``.
    path : str or Path, optional
        Where to save the figure (then it is closed; see :mod:`cable_ocp.plots`).

    Raises
    ------
    TypeError
        ``trajectory`` is not a :class:`LineTrajectory`.
    """
    if not isinstance(trajectory, LineTrajectory):
        raise TypeError(
            f"line_run: trajectory must be a LineTrajectory (a run of a scene with "
            f"[winch.line]); got {type(trajectory).__name__}"
        )
    mesh = trajectory.scene.winch.line.mesh
    time = trajectory.time
    fig, axes = plt.subplots(2, 2, figsize=(11, 6.5), sharex=True)
    ax = axes[0, 0]
    ax.plot(time, trajectory.line_out, color="k", label="line out L_out")
    ax.set_ylabel("line out [m]")
    count_axis = ax.twinx()
    count_axis.step(time, trajectory.element_count, where="post", color="tab:red", lw=0.8)
    count_axis.set_ylabel("n (elements 0..n)", color="tab:red")
    ax.set_title("line out and element count")
    ax = axes[0, 1]
    ax.plot(time, trajectory.top_length, color="k", lw=0.8)
    for bound, text in ((mesh.top_length_min, "l_min"), (mesh.top_length_max, "l_min + 3/2 Delta")):
        ax.axhline(bound, color="tab:gray", ls=":", lw=0.8)
        ax.annotate(text, (time[0], bound), fontsize=8, va="bottom")
    ax.set_ylabel("top element l_n [m]")
    ax.set_title(f"top element (Delta = {mesh.element_length:g} m): splits and merges")
    ax = axes[1, 0]
    ax.plot(time, trajectory.top_tension / 1e3, color="k", lw=0.8)
    ax.set_ylabel("top tension [kN]")
    ax.set_xlabel("t [s]")
    ax = axes[1, 1]
    ax.plot(time, trajectory.end[:, 2], color="k", lw=0.8)
    ax.set_ylabel("end height z_E [m]")
    ax.set_xlabel("t [s]")
    for ax in axes.flat:
        ax.grid(alpha=0.3)
    fig.suptitle(f"{trajectory.scene_name}: a line paid out and hauled in by elements")
    fig.tight_layout()
    return finish_figure(fig, path)
