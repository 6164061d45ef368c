"""Figures of a survey scene: the seabed surface in 3D with the cable and the end's path.

The seabed is the scene's ``[seabed]`` section (a bathymetry grid plus hills, or hills alone on
the level the end's start fixes, CONVENTIONS.md §5), drawn over the ground the run covers. The
cable is 300 m long and the seabed's relief a few metres, so by default the view shows the
bottom ``window`` metres of water, where the end works; the cable's upper part leaves the box.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from cable_ocp.plots import finish_figure
from cable_ocp.scene.schema import Seabed
from cable_ocp.simulation.seabed import bathymetry, clearance_reference, seabed_elevation
from cable_ocp.simulation.trajectory import Trajectory

MARGIN = 25.0  # m of seabed drawn around the ground the run covers
SAMPLES = 90  # surface points along each axis


def _ground(trajectory: Trajectory, seabed: Seabed) -> tuple[np.ndarray, np.ndarray]:
    """Axes (m) of the seabed patch under the run, inside the grid where there is one."""
    low = trajectory.end[:, :2].min(axis=0) - MARGIN
    high = trajectory.end[:, :2].max(axis=0) + MARGIN
    grid = bathymetry(seabed)
    if grid is not None:
        low = np.maximum(low, [grid.x[0], grid.y[0]])
        high = np.minimum(high, [grid.x[-1], grid.y[-1]])
    return np.linspace(low[0], high[0], SAMPLES), np.linspace(low[1], high[1], SAMPLES)


def seabed_view(
    trajectory: Trajectory,
    seabed: Seabed,
    times: Sequence[float] | None = None,
    window: float | None = 40.0,
    path: str | Path | None = None,
) -> Figure:
    """The seabed surface in 3D, the cable's shapes at chosen times and the end's path.

    Parameters
    ----------
    trajectory : Trajectory
    seabed : Seabed
        The scene's ``[seabed]`` section.
    times : sequence of float, s, optional
        When to draw the cable (default: six times over the run).
    window : float or None, m
        Height of the box above the seabed's highest drawn point; None shows the whole cable.
    path : path, optional
        Save the figure there and close it.
    """
    reference = clearance_reference(seabed, trajectory.end[0])
    x, y = _ground(trajectory, seabed)
    X, Y = np.meshgrid(x, y, indexing="ij")
    Z = seabed_elevation(seabed, X, Y, reference)
    top = np.inf if window is None else Z.max() + window
    fig = plt.figure(figsize=(10, 7))
    ax = fig.add_subplot(projection="3d")
    ax.plot_surface(X, Y, Z, cmap="terrain", alpha=0.75, linewidth=0, rstride=2, cstride=2)
    times = np.linspace(0, trajectory.time[-1], 6) if times is None else np.asarray(times)
    for t in times:
        k = int(np.argmin(np.abs(trajectory.time - t)))
        joints = trajectory.joints[k].copy()
        joints[:, joints[2] > top] = np.nan  # the part above the box is not drawn
        ax.plot(*joints, "-", lw=1.5, label=f"cable, t = {trajectory.time[k]:.0f} s")
    end = trajectory.end
    ax.plot(end[:, 0], end[:, 1], end[:, 2], "k", lw=1.2, label="end E")
    ground = seabed_elevation(seabed, end[:, 0], end[:, 1], reference)
    ax.plot(end[:, 0], end[:, 1], ground, "k:", lw=0.8, label="seabed under the end")
    ax.set_xlim(x[0], x[-1])
    ax.set_ylim(y[0], y[-1])
    if window is not None:
        ax.set_zlim(Z.min() - 2, top)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_zlabel("z [m]")
    ax.set_title(f"{trajectory.scene_name}: seabed, cable and end")
    ax.legend(fontsize=8, loc="upper left")
    return finish_figure(fig, path)
