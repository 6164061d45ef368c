"""Figures of results (matplotlib): the paper's Fig. 14, 17 and 18 and more; :func:`animate`.

Every function takes one or more :class:`~cable_ocp.simulation.trajectory.Trajectory` objects and
returns the figure. Importing this module never selects a matplotlib backend: matplotlib chooses one
(Agg without a display, so the command line and the tests run headless; inline in a notebook).

Who closes a figure:

- with ``path`` (png, pdf or svg by the suffix) the figure is saved there and closed, so that batch
  runs (the command line, the studies) leave no figures open; the returned figure can still be
  shown, e.g. by ``IPython.display.display(fig)``;
- without ``path`` the figure stays open in pyplot like any ``plt.subplots`` figure: a notebook
  shows it when the cell ends (or at ``plt.show()``), a script shows it at ``plt.show()``. End a
  notebook cell with ``plt.show()`` rather than with the returned figure, which would show it twice.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from cable_ocp.plots.animation import animate as animate  # a GIF of the run
from cable_ocp.scene.schema import Seabed
from cable_ocp.simulation.seabed import bathymetry, clearance_reference, seabed_elevation
from cable_ocp.simulation.trajectory import Trajectory


def finish_figure(fig: Figure, path: str | Path | None) -> Figure:
    """Lay out ``fig``; with a ``path``, save it there and close it (the module's rule)."""
    fig.tight_layout()
    # tight_layout leaves a placeholder layout engine, for which savefig lays the figure out in
    # a draw of its own before drawing it; without an engine the same pixels take one draw.
    fig.set_layout_engine(None)
    if path is not None:
        fig.savefig(path, dpi=120)
        plt.close(fig)
    return fig


def _labelled(trajectories, labels):
    trajectories = [trajectories] if isinstance(trajectories, Trajectory) else list(trajectories)
    labels = list(labels) if labels else [t.scene_name for t in trajectories]
    return list(zip(trajectories, labels, strict=True))


def end_trajectory(
    trajectories: Trajectory | Sequence[Trajectory],
    labels: Sequence[str] | None = None,
    path: str | Path | None = None,
) -> Figure:
    """End E in the xy, xz and yz planes (the paper's Fig. 14), with the top path in xy."""
    fig, axes = plt.subplots(1, 3, figsize=(14, 4.2))
    for traj, label in _labelled(trajectories, labels):
        end = traj.end
        axes[0].plot(end[:, 0], end[:, 1], label=f"{label}: end E")
        axes[1].plot(end[:, 0], end[:, 2], label=label)
        axes[2].plot(end[:, 1], end[:, 2], label=label)
    axes[0].plot(traj.top[:, 0], traj.top[:, 1], "k--", lw=0.8, label="top (vessel)")
    for ax, (a, b) in zip(axes, [("x", "y"), ("x", "z"), ("y", "z")], strict=True):
        ax.set_xlabel(f"{a} [m]")
        ax.set_ylabel(f"{b} [m]")
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    axes[0].set_title("plane xy")
    axes[1].set_title("plane xz")
    axes[2].set_title("plane yz")
    return finish_figure(fig, path)


def clearance(
    trajectories: Trajectory | Sequence[Trajectory],
    clearance_depth: float = 5.0,
    labels: Sequence[str] | None = None,
    path: str | Path | None = None,
    minimum_clearance: float | None = None,
) -> Figure:
    """Height of the end above the seabed, ``delta + e(t)`` (eq. 39), against the target.

    ``minimum_clearance`` (m, ``seabed.minimum_clearance``) draws the hard minimum c_min too.
    """
    fig, ax = plt.subplots(figsize=(9, 4))
    for traj, label in _labelled(trajectories, labels):
        ax.plot(
            traj.time,
            clearance_depth + traj.clearance_error,
            label=f"{label} (Omega = {traj.omega:.3f} m)",
        )
    ax.axhline(
        clearance_depth, color="k", ls="--", lw=0.8, label=f"target delta = {clearance_depth} m"
    )
    if minimum_clearance is not None:
        ax.axhline(
            minimum_clearance, color="r", lw=1.2, label=f"minimum c_min = {minimum_clearance} m"
        )
    ax.set_ylabel("end height above the seabed [m]")
    ax.set_xlabel("t [s]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    return finish_figure(fig, path)


def cable_shapes(
    trajectory: Trajectory,
    times: Sequence[float] | None = None,
    seabed: Seabed | None = None,
    path: str | Path | None = None,
) -> Figure:
    """Cable shapes in the xz plane at chosen times, with the seabed under the end (Fig. 18).

    ``seabed`` is the scene's ``[seabed]`` section (default: flat, delta = 5 m under the start);
    a grid's seabed is drawn where the grid reaches.
    """
    seabed = Seabed() if seabed is None else seabed
    reference = clearance_reference(seabed, trajectory.end[0])
    times = np.linspace(0, trajectory.time[-1], 6) if times is None else np.asarray(times)
    fig, ax = plt.subplots(figsize=(10, 5))
    for t in times:
        k = int(np.argmin(np.abs(trajectory.time - t)))
        joints = trajectory.joints[k]
        (line,) = ax.plot(joints[0], joints[2], "-o", ms=2, label=f"t = {trajectory.time[k]:.0f} s")
        ground = seabed_elevation(seabed, joints[0, 0], joints[1, 0], reference)
        ax.plot(joints[0, 0], ground, "v", color=line.get_color())
    low, high = trajectory.joints[:, 0].min() - 20, trajectory.joints[:, 0].max() + 20
    grid = bathymetry(seabed)
    if grid is not None:
        low, high = max(low, grid.x[0]), min(high, grid.x[-1])
    x = np.linspace(low, high, 400)
    path_y = np.interp(x, trajectory.end[:, 0], trajectory.end[:, 1])
    if grid is not None:
        path_y = np.clip(path_y, grid.y[0], grid.y[-1])
    ground = seabed_elevation(seabed, x, path_y, reference)
    ax.fill_between(
        x, ground.min() - 5, ground, color="tan", alpha=0.5, label="seabed under the end's path"
    )
    ax.set_xlabel("x [m]")
    ax.set_ylabel("z [m]")
    ax.set_title("cable shapes (markers ▼: seabed under the end)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, ncol=2)
    return finish_figure(fig, path)


def winch_angle(
    trajectories: Trajectory | Sequence[Trajectory],
    labels: Sequence[str] | None = None,
    bounds: tuple[float, float] | None = None,
    path: str | Path | None = None,
) -> Figure:
    """Winch angle versus time (the paper's Fig. 17), with the angle bounds."""
    fig, ax = plt.subplots(figsize=(9, 4))
    for traj, label in _labelled(trajectories, labels):
        ax.plot(traj.time, traj.winch_angle, label=label)
    if bounds is not None:
        for b in bounds:
            ax.axhline(b, color="k", ls=":", lw=0.8)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("winch angle phi [rad]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    return finish_figure(fig, path)


def catenary_comparison(
    model_points: np.ndarray, analytic_points: np.ndarray, path: str | Path | None = None
) -> Figure:
    """Model joints against the analytic catenary (the paper's Fig. 7b).

    Parameters
    ----------
    model_points : array (2, k), m
        x and z of the model's joints.
    analytic_points : array (2, m), m
        x and z along the analytic catenary.
    """
    fig, ax = plt.subplots(figsize=(6, 5))
    ax.plot(*analytic_points, "k-", label="analytic elastic catenary (eq. 34)")
    ax.plot(*model_points, "o", ms=4, label="rfe model joints")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("z [m]")
    ax.set_aspect("equal")
    ax.grid(alpha=0.3)
    ax.legend()
    return finish_figure(fig, path)
