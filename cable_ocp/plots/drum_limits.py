"""The drum's rate and acceleration against the winch's limits (matplotlib).

Where a run's drum rides a limit is seen rather than read: a closed loop in seas steeper than
the winch can follow sits on ``winch.rate_max`` or ``winch.acceleration_max`` for as long as the
sea asks for more (its result's ``saturation`` says when), and an optimum rides the bounds that
its solve held. By the rules of :mod:`cable_ocp.plots`: the function returns the figure; with
``path`` it is saved there and closed.
"""

from __future__ import annotations

import textwrap
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from cable_ocp.model.layout import INPUTS
from cable_ocp.plots import labelled_runs, run_title, significant
from cable_ocp.plots.figure import finish_figure
from cable_ocp.simulation.trajectory import Trajectory

if TYPE_CHECKING:  # results are told by what they hold (cable_ocp.plots): no solver is loaded
    from cable_ocp.control.closed_loop.result import MpcResult
    from cable_ocp.control.optimization import OcpResult

# A drum within this share of a limit is on it (the closed loop's drum clips to the limit exactly;
# an optimum's bound rows hold at its RK4 points).
ON_LIMIT = 0.01


def drum_use(
    runs: Trajectory | OcpResult | MpcResult | Sequence[Trajectory | OcpResult | MpcResult],
    labels: Sequence[str] | None = None,
    path: str | Path | None = None,
) -> Figure:
    """The drum's rate phi' and acceleration phi'' over time, with the winch's limits.

    Parameters
    ----------
    runs : Trajectory, OcpResult or MpcResult, or a sequence of them
        Runs of one scene's winch (the limits drawn are the first run's scene's
        ``winch.rate_max`` and ``winch.acceleration_max``, rad/s and rad/s^2; none where it sets
        none). A closed loop's drum is the plant's, heave feedback and saturation included.
    labels : sequence of str, optional
        One per run (default: what each run is).
    path : path-like, optional
        Where to save the figure (then closed).

    Raises
    ------
    ValueError
        A run holds no trajectory (a failed optimisation's), or no winch inputs (a result of an
        earlier format kept only its end and top).
    TypeError
        A run is a line paid out by elements (``LineTrajectory``).
    """
    runs = labelled_runs(runs, labels)
    for run, trajectory, _ in runs:
        if not isinstance(trajectory, Trajectory):
            raise TypeError(
                f"drum_use draws a Trajectory, OcpResult or MpcResult, not {type(run).__name__} "
                "(a line paid out by elements: plots.line_run)"
            )
    trajectories, labels = [t for _, t, _ in runs], [label for _, _, label in runs]
    winch = trajectories[0].scene.winch
    limits = (winch.rate_max, winch.acceleration_max)
    fig, axes = plt.subplots(2, 1, figsize=(13, 6.4), sharex=True)
    for index, (run, trajectory, label) in enumerate(runs):
        series = drum_rates(trajectory, winch.drum_radius)
        saturation = getattr(run, "saturation", "")
        for ax, values, limit in zip(axes, series, limits, strict=True):
            share = f"at or past the limit {on_limit_share(values, limit):.0%} of the time"
            text = label if limit is None else f"{label}: {share}"
            ax.plot(trajectory.time, values, color=f"C{index}", lw=0.9, label=text)
        if saturation:
            axes[0].plot([], [], " ", label=textwrap.fill(f"{label}: {saturation}", 50))
    names = ("rate phi' [rad/s]", "acceleration phi'' [rad/s^2]")
    fields = ("winch.rate_max", "winch.acceleration_max")
    for ax, limit, name, field in zip(axes, limits, names, fields, strict=True):
        if limit is not None:
            ax.axhline(limit, color="k", ls="--", lw=0.9, label=f"{field} = {significant(limit)}")
            ax.axhline(-limit, color="k", ls="--", lw=0.9)
        else:
            ax.plot([], [], " ", label=f"{field}: none set")
        ax.set_ylabel(f"drum {name}")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1))  # beside the curves
    axes[0].set_title(run_title("the drum against the winch's limits",
                                [t.scene_name for t in trajectories], labels))  # fmt: skip
    axes[-1].set_xlabel("t [s]")
    return finish_figure(fig, path)


def drum_rates(trajectory: Trajectory, drum_radius: float) -> tuple[np.ndarray, np.ndarray]:
    """The drum's rate (rad/s) and acceleration (rad/s^2) at a run's steps, from its inputs.

    The top element's length rate and acceleration over the drum's radius ``drum_radius`` (m):
    the line the drum pays out (a heave compensation's included).
    """
    rows = [INPUTS.top_length_rate, INPUTS.top_length_acceleration]
    rate, acceleration = np.asarray(trajectory.inputs, dtype=float)[:, rows].T / drum_radius
    if not (np.all(np.isfinite(rate)) and np.all(np.isfinite(acceleration))):
        raise ValueError(
            f"{trajectory.scene_name} holds no winch inputs at its steps (a closed loop's file of "
            "result format 1 or 2 kept only its end and top): its drum cannot be drawn"
        )
    return rate, acceleration


def on_limit_share(values: np.ndarray, limit: float | None) -> float:
    """The share of ``values`` at ``+-limit`` or past it, to :data:`ON_LIMIT` (0 without a limit).

    Past it: another run drawn against the first run's limits (the same sea on a winch without
    them).
    """
    if limit is None or np.size(values) == 0:
        return 0.0
    return float(np.mean(np.abs(values) >= (1 - ON_LIMIT) * limit))
