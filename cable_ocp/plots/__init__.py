"""Figures of results (matplotlib): the paper's Fig. 14, 17 and 18 and more; :func:`animate`.

Every function takes one or more runs and returns the figure: a
:class:`~cable_ocp.simulation.trajectory.Trajectory`, or a result that carries one (an
``OcpResult``'s verified run, an ``MpcResult``'s plant run; its planned angle too in
:func:`winch_angle`), so that an open loop and a closed loop are drawn by the same functions. The
figures of the closed loop's solves are in :mod:`cable_ocp.plots.closed_loop`, the drum against the
winch's limits in :mod:`cable_ocp.plots.drum_limits`, the top tension against its static value in
:mod:`cable_ocp.plots.tension`. Importing this module never selects a matplotlib backend: matplotlib
chooses one (Agg without a display, so the command line and the tests run headless; inline in a
notebook).

Who closes a figure:

- with ``path`` (png, pdf or svg by the suffix) the figure is saved there and closed, so that batch
  runs (the command line, the studies) leave no figures open; the returned figure can still be
  shown, e.g. by ``IPython.display.display(fig)``;
- without ``path`` the figure stays open in pyplot like any ``plt.subplots`` figure: a notebook
  shows it when the cell ends (or at ``plt.show()``), a script shows it at ``plt.show()``. End a
  notebook cell with ``plt.show()`` rather than with the returned figure, which would show it twice.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from cable_ocp.plots.animation import animate as animate  # a GIF of the run
from cable_ocp.plots.figure import finish_figure as finish_figure  # lay out, save, close
from cable_ocp.plots.line import line_run as line_run  # a line paid out by elements
from cable_ocp.scene.schema import Seabed
from cable_ocp.simulation.line_trajectory import LineTrajectory
from cable_ocp.simulation.seabed import bathymetry, clearance_reference, seabed_elevation
from cable_ocp.simulation.trajectory import Trajectory

if TYPE_CHECKING:  # the results are told by what they hold, so that figures load no solver
    from cable_ocp.control.closed_loop.result import MpcResult
    from cable_ocp.control.optimization import OcpResult

    # What a figure draws: a run, or a result that carries one (module docstring).
    Run = Trajectory | LineTrajectory | OcpResult | MpcResult


def significant(value: float, digits: int = 3) -> str:
    """``value`` with ``digits`` significant figures, for legends and titles.

    Fixed point from 1e-3 to 1e5 (``4.71``, ``0.0234``), else a power of ten (``1.30e-4``): a
    small Omega is never shown as ``0.000``.
    """
    value = float(value)
    if not math.isfinite(value) or value == 0:
        return f"{value:g}"
    exponent = math.floor(math.log10(abs(value)))
    if -3 <= exponent < 5:
        return f"{value:.{max(digits - 1 - exponent, 0)}f}"
    mantissa, power = f"{value:.{digits - 1}e}".split("e")
    return f"{mantissa}e{int(power)}"


def run_label(trajectory: Trajectory) -> str:
    """What a run did with its winch: ``winch locked`` or ``winch profile``."""
    angle = np.asarray(trajectory.winch_angle)
    return "winch locked" if angle.size == 0 or np.ptp(angle) == 0 else "winch profile"


def run_title(what: str, scenes: Sequence[str | None], runs: Sequence[str]) -> str:
    """A figure's title: what it shows, the scene (or scenes) and the run (or runs) it shows.

    A scene of None (a result that does not know its scene, and was not told) is left out.
    """
    scene = ", ".join(dict.fromkeys(s for s in scenes if s))
    run = " vs ".join(dict.fromkeys(runs))
    return f"{what}\nscene {scene}: {run}" if scene else f"{what}\n{run}"


def result_label(result) -> str:
    """What a result's run is: ``closed loop (SOLVER)`` or ``optimised (SOLVER)``."""
    if _closed_loop(result):
        return f"closed loop ({result.settings.get('solver', 'solver not recorded')})"
    return f"optimised ({result.solver or result.method})"


def _closed_loop(run) -> bool:
    """Whether a run is an ``MpcResult`` (it holds its solves)."""
    return hasattr(run, "solves") and hasattr(run, "planned_angle")


def _run_of(run) -> Trajectory | LineTrajectory:
    """The trajectory of a run: itself, or the one a result carries."""
    if isinstance(run, Trajectory | LineTrajectory):
        return run
    if getattr(run, "trajectory", None) is None:
        raise ValueError(f"{type(run).__name__} holds no run to draw (no verified trajectory)")
    return run.trajectory


def labelled_runs(runs, labels) -> list[tuple[object, Trajectory | LineTrajectory, str]]:
    """``(run, its trajectory, its label)`` of one run or several (module docstring).

    The labels default to what each run is (its scene's name first where the runs' scenes
    differ); ValueError names a run that holds no trajectory (a failed optimisation's).
    """
    one = isinstance(runs, Trajectory | LineTrajectory) or hasattr(runs, "trajectory")
    runs = [runs] if one else list(runs)
    trajectories = [_run_of(run) for run in runs]
    if labels:
        labels = list(labels)
    else:
        labels = [run_label(t) if t is run else result_label(run)
                  for run, t in zip(runs, trajectories, strict=True)]  # fmt: skip
        if len({_scene(t) for t in trajectories}) > 1:
            labels = [
                f"{_scene(t)}, {label}" for t, label in zip(trajectories, labels, strict=True)
            ]
    return list(zip(runs, trajectories, labels, strict=True))


def _labelled(runs, labels) -> list[tuple[Trajectory | LineTrajectory, str]]:
    """``(trajectory, label)`` of one run or several."""
    return [(trajectory, label) for _, trajectory, label in labelled_runs(runs, labels)]


def _scene(run) -> str | None:
    """The scene of a run: a Trajectory's name; None for a run that does not know it."""
    return getattr(run, "scene_name", None)


def _title(ax, what: str, pairs) -> None:
    ax.set_title(run_title(what, [_scene(t) for t, _ in pairs], [label for _, label in pairs]))


def end_trajectory(
    trajectories: Run | Sequence[Run],
    labels: Sequence[str] | None = None,
    path: str | Path | None = None,
) -> Figure:
    """End E in the xy, xz and yz planes (the paper's Fig. 14), with the top path in xy."""
    fig, axes = plt.subplots(1, 3, figsize=(14, 4.6))
    pairs = _labelled(trajectories, labels)
    for traj, label in pairs:
        end = traj.end
        axes[0].plot(end[:, 0], end[:, 1], label=f"{label}: end E")
        axes[1].plot(end[:, 0], end[:, 2], label=label)
        axes[2].plot(end[:, 1], end[:, 2], label=label)
    axes[0].plot(traj.top[:, 0], traj.top[:, 1], "k--", lw=0.8, label="top (vessel)")
    fig.suptitle(run_title("end E (the paper's Fig. 14)", [_scene(t) for t, _ in pairs],
                           [label for _, label in pairs]).replace("\n", ", "))  # fmt: skip
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
    trajectories: Run | Sequence[Run],
    clearance_depth: float = 5.0,
    labels: Sequence[str] | None = None,
    path: str | Path | None = None,
    minimum_clearance: float | None = None,
    zoom: bool = False,
) -> Figure:
    """Height of the end above the seabed, ``delta + e(t)`` (eq. 39), against the target.

    ``minimum_clearance`` (m, ``seabed.minimum_clearance``) draws the hard minimum c_min too.
    With ``zoom`` a lower panel zooms on the runs within 10 times the largest error of the best
    run (a locked winch is metres off a closed loop's centimetres).
    """
    fig, axes = plt.subplots(2 if zoom else 1, 1, figsize=(10, 6.8) if zoom else (9, 4.4),
                             sharex=True, squeeze=False)  # fmt: skip
    axes = axes[:, 0]
    pairs = _labelled(trajectories, labels)
    scale = 10 * min(np.max(np.abs(traj.clearance_error)) for traj, _ in pairs)
    for index, (traj, label) in enumerate(pairs):
        shown = [axes[0]]
        if zoom and np.max(np.abs(traj.clearance_error)) <= scale:
            shown.append(axes[1])
        for ax in shown:
            ax.plot(traj.time, clearance_depth + traj.clearance_error, color=f"C{index}",
                    label=f"{label} (Omega = {significant(traj.omega)} m)")  # fmt: skip
    for ax in axes:
        ax.axhline(clearance_depth, color="k", ls="--", lw=0.8,
                   label=f"target delta = {clearance_depth} m")  # fmt: skip
        if minimum_clearance is not None:
            ax.axhline(minimum_clearance, color="r", lw=1.2,
                       label=f"minimum c_min = {minimum_clearance} m")  # fmt: skip
        ax.set_ylabel("end height above the seabed [m]")
        ax.ticklabel_format(axis="y", useOffset=False)  # heights as they are, not "+5" and 1e-4
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    _title(axes[0], "height of the end E above the seabed (eq. 39)", pairs)
    if zoom:
        axes[1].set_ylabel("end height above the seabed [m] (zoom)")
    axes[-1].set_xlabel("t [s]")
    return finish_figure(fig, path)


def cable_shapes(
    trajectory: Run,
    times: Sequence[float] | None = None,
    seabed: Seabed | None = None,
    path: str | Path | None = None,
    label: str | None = None,
) -> Figure:
    """Cable shapes in the xz plane at chosen times, with the seabed under the end (Fig. 18).

    ``seabed`` is the scene's ``[seabed]`` section (default: flat, delta = 5 m under the start);
    a grid's seabed is drawn where the grid reaches. ``label`` names the run in the title
    (default: ``run_label``, or what a result's run is).
    """
    if not isinstance(trajectory, Trajectory | LineTrajectory):
        label, trajectory = label or result_label(trajectory), _run_of(trajectory)
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
    # nanmin: a line paid out by elements pads each sample's joints after its top with NaN
    low, high = np.nanmin(trajectory.joints[:, 0]) - 20, np.nanmax(trajectory.joints[:, 0]) + 20
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
    _title(ax, "cable shapes in the xz plane (markers ▼: the seabed under the end)",
           [(trajectory, label or run_label(trajectory))])  # fmt: skip
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, ncol=2)
    return finish_figure(fig, path)


def winch_angle(
    trajectories: Run | Sequence[Run],
    labels: Sequence[str] | None = None,
    bounds: tuple[float, float] | None = None,
    path: str | Path | None = None,
) -> Figure:
    """Winch angle versus time (the paper's Fig. 17), with the angle bounds (dotted).

    ``bounds`` is ``(winch.angle_min, winch.angle_max)``, rad (a closed loop's
    ``angle_range``). A closed loop's angle is the one applied (heave feedback included); its
    controller's plan is drawn beside it. An optimum on non-uniform Hermite nodes (an adaptive
    grid's, ``OcpResult.nodes``) has its nodes marked on its angle.
    """
    fig, ax = plt.subplots(figsize=(9, 4.4))
    runs = labelled_runs(trajectories, labels)
    pairs = [(traj, label) for _, traj, label in runs]
    for run, traj, label in runs:
        if _closed_loop(run):
            ax.plot(traj.time, traj.winch_angle, lw=0.9, label=f"{label}, applied")
            ax.plot(traj.time, run.planned_angle, lw=1.6, label=f"{label}, planned")
        else:
            (line,) = ax.plot(traj.time, traj.winch_angle, label=label)
            _mark_nodes(ax, run, traj, line.get_color(), label)
    if bounds is not None:
        low, high = bounds
        text = f"winch bounds phi_min = {low:g} rad, phi_max = {high:g} rad"
        for k, b in enumerate(bounds):
            ax.axhline(b, color="k", ls=":", lw=0.8, label=text if k == 0 else None)
    _title(ax, "winch angle (the paper's Fig. 17)", pairs)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("winch angle phi [rad]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    return finish_figure(fig, path)


def _mark_nodes(ax, run, trajectory: Trajectory, color: str, label: str) -> None:
    """Mark an optimum's non-uniform Hermite nodes (``OcpResult.nodes``, s) on its angle."""
    nodes = np.asarray(getattr(run, "nodes", ()), dtype=float)
    if nodes.size == 0:
        return
    angle = np.interp(nodes, trajectory.time, trajectory.winch_angle)
    text = f"{label}: its {nodes.size - 1} control intervals' nodes"
    ax.plot(nodes, angle, "o", ms=3.5, mfc="none", color=color, label=text)


def catenary_comparison(
    model_points: np.ndarray,
    analytic_points: np.ndarray,
    path: str | Path | None = None,
    scene_name: str = "catenary",
    elements: int | None = None,
) -> Figure:
    """Model joints against the analytic catenary (the paper's Fig. 7b).

    Parameters
    ----------
    model_points : array (2, k), m
        x and z of the model's joints.
    analytic_points : array (2, m), m
        x and z along the analytic catenary.
    path : path-like, optional
        Where to save the figure (then closed).
    scene_name : str
        The scene, named in the title.
    elements : int, optional
        The model's n, named in the title and the legend (default: from the joints, k - 2).
    """
    n = len(np.asarray(model_points)[0]) - 2 if elements is None else elements
    fig, ax = plt.subplots(figsize=(6, 6.2))
    ax.plot(*analytic_points, "k-", label="analytic elastic catenary (eq. 34)")
    ax.plot(*model_points, "o", ms=4, label=f"rfe model joints, n = {n}")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("z [m]")
    ax.set_aspect("equal")
    ax.grid(alpha=0.3)
    ax.set_title(run_title("statics against the analytic catenary", [scene_name],
                           [f"static equilibrium, n = {n}"]))  # fmt: skip
    # Below the axes: inside, the legend covered the curve's top and the z tick labels.
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.1), ncol=1, fontsize=9, frameon=False)
    return finish_figure(fig, path)
