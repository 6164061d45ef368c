"""An animation of a run: the cable's shape, the end's path and the seabed over time (GIF).

The seabed is the one under the end's path, read from the trajectory itself: by eq. 39 the seabed
under the end lies ``z_E(t) - e(t) - delta`` high, ``delta`` the clearance the end starts at
(``seabed.clearance``, which only places the seabed in the picture).
"""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.animation import FuncAnimation, PillowWriter

from cable_ocp.simulation.line_trajectory import LineTrajectory
from cable_ocp.simulation.trajectory import Trajectory

FRAMES = 40
FPS = 12


def animate(
    trajectory: Trajectory | LineTrajectory,
    path: str | Path | None = None,
    clearance_depth: float = 5.0,
    frames: int = FRAMES,
    fps: int = FPS,
) -> FuncAnimation:
    """Animate the cable in the vertical x-z plane over the run (matplotlib, Pillow writer).

    Parameters
    ----------
    trajectory : Trajectory or LineTrajectory
        A line paid out by elements
        (:class:`~cable_ocp.simulation.line_trajectory.LineTrajectory`) is drawn with the
        elements of each sample, and its n in the label.
    path : str or Path, optional
        A ``.gif`` to write (then the figure is closed); without it the animation is returned
        with its figure open, e.g. for ``IPython.display.HTML(animation.to_jshtml())``.
    clearance_depth : float, m
        How far below the end's start the seabed lies (``seabed.clearance``).
    frames : int
        Frames, spread evenly over the run's output times.
    fps : int
        Frames per second of the GIF.

    Returns
    -------
    matplotlib.animation.FuncAnimation

    Raises
    ------
    TypeError
        ``trajectory`` is neither a Trajectory nor a LineTrajectory.
    ValueError
        ``frames`` or ``fps`` below 1.
    """
    if not isinstance(trajectory, Trajectory | LineTrajectory):
        raise TypeError(
            f"animate: trajectory must be a Trajectory or a LineTrajectory (a run, e.g. "
            f"co.simulate(scene)); got {type(trajectory).__name__}"
        )
    if frames < 1 or fps < 1:
        raise ValueError(f"frames = {frames}, fps = {fps}: both must be >= 1")
    joints, end, time = trajectory.joints, trajectory.end, trajectory.time
    shown = np.unique(np.linspace(0, time.size - 1, min(frames, time.size)).round().astype(int))
    ground = end[:, 2] - trajectory.clearance_error - clearance_depth  # under the end (eq. 39)
    order = np.argsort(end[:, 0], kind="stable")
    low, high = np.nanmin(joints[:, 0]), np.nanmax(joints[:, 0])
    margin = 0.05 * max(high - low, 1.0)
    x = np.linspace(low - margin, high + margin, 300)
    seabed = np.interp(x, end[order, 0], ground[order])
    bottom = min(seabed.min(), np.nanmin(joints[:, 2])) - 2 * margin
    top = max(np.nanmax(joints[:, 2]), 0.0) + margin
    counts = getattr(trajectory, "element_count", None)  # a line paid out by elements

    fig, ax = plt.subplots(figsize=(8, 4))
    ax.fill_between(x, bottom, seabed, color="tan", alpha=0.6, label="seabed under the end's path")
    ax.axhline(0.0, color="tab:blue", lw=0.8, alpha=0.5)  # the sea surface
    (trace,) = ax.plot([], [], color="tab:orange", lw=1, label="path of the end")
    (cable,) = ax.plot([], [], "-", color="k", lw=1.5, marker="o", ms=1.5, label="cable")
    (tip,) = ax.plot([], [], "o", color="tab:red", ms=4)
    label = ax.text(0.01, 0.97, "", transform=ax.transAxes, va="top")
    ax.set_xlim(x[0], x[-1])
    ax.set_ylim(bottom, top)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("z [m]")
    ax.set_title(f"{trajectory.scene_name}: cable, end and seabed")
    ax.legend(loc="lower right", fontsize=8)
    fig.tight_layout()

    def draw(k: int):
        cable.set_data(joints[k, 0], joints[k, 2])
        trace.set_data(end[: k + 1, 0], end[: k + 1, 2])
        tip.set_data(end[k : k + 1, 0], end[k : k + 1, 2])
        label.set_text(f"t = {time[k]:.1f} s" + ("" if counts is None else f", n = {counts[k]}"))
        return cable, trace, tip, label

    animation = FuncAnimation(fig, draw, frames=shown, interval=1000 / fps, blit=True)
    if path is not None:
        animation.save(path, writer=PillowWriter(fps=fps), dpi=80)
        plt.close(fig)
    return animation
