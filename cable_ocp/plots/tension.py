"""The top tension against the rope's static tension and DNV's slack line (matplotlib).

An offshore engineer reads a run by its tension first: how far it swings about the static value
(the submerged weight that hangs below the top), whether it dips under 10 % of static
(DNV-RP-H103 §5's slack criterion: snap loads follow), and whether the rope pushes, which no
rope can (the run then fails, :mod:`cable_ocp.simulation.slack`). By the rules of
:mod:`cable_ocp.plots`: the function returns the figure; with ``path`` it is saved there and
closed.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from cable_ocp.model.cable import spec_from_scene
from cable_ocp.plots import labelled_runs, run_title, significant
from cable_ocp.plots.figure import finish_figure
from cable_ocp.simulation.line_trajectory import LineTrajectory
from cable_ocp.simulation.slack import SLACK_FRACTION, run_static, top_values
from cable_ocp.simulation.trajectory import Trajectory

if TYPE_CHECKING:  # results are told by what they hold (cable_ocp.plots): no solver is loaded
    from cable_ocp.control.closed_loop.result import MpcResult
    from cable_ocp.control.optimization import OcpResult

    Run = Trajectory | LineTrajectory | OcpResult | MpcResult


def tension_against_static(
    runs: Run | Sequence[Run],
    labels: Sequence[str] | None = None,
    path: str | Path | None = None,
) -> Figure:
    """Signed top tension over time (kN), with its static value and the slack line.

    Each run is drawn with its static top tension (dashed: the submerged weight below the top
    at its line out) and 10 % of it (dotted, DNV-RP-H103 §5); the legend gives its least and
    largest tension as shares of static. Zero and the push at which a run fails (the first
    run's :func:`~cable_ocp.simulation.slack.compression_tolerance`) are drawn where a run comes
    near them.

    Parameters
    ----------
    runs : Trajectory, LineTrajectory, OcpResult or MpcResult, or a sequence of them
        Each with its scene (the static tension is the scene's rope and payload).
    labels : sequence of str, optional
        One per run (default: what each run is).
    path : path-like, optional
        Where to save the figure (then closed).

    Raises
    ------
    ValueError
        A run holds no trajectory (a failed optimisation's), no scene (a file written before
        scenes were kept), or no tensions (a closed loop's file of format 1 or 2 kept only its
        end and top).
    """
    runs = labelled_runs(runs, labels)
    trajectories, labels = [t for _, t, _ in runs], [label for _, _, label in runs]
    fig, ax = plt.subplots(figsize=(10, 4.8))
    lowest = np.inf
    for index, (trajectory, label) in enumerate(zip(trajectories, labels, strict=True)):
        tension = trajectory.top_tension
        if not np.isfinite(tension).any():
            raise ValueError(
                f"{trajectory.scene_name} holds no tensions (a closed loop's file of result "
                "format 1 or 2 kept only its end and top): its tension cannot be drawn"
            )
        static = top_values(run_static(trajectory, spec_from_scene(trajectory.scene)))
        colour = f"C{index}"
        share = _shares(tension, static)
        ax.plot(trajectory.time, 1e-3 * tension, color=colour, lw=1.0, label=f"{label}: {share}")
        ax.plot(trajectory.time, 1e-3 * static, color=colour, ls="--", lw=0.8)
        ax.plot(trajectory.time, 1e-3 * SLACK_FRACTION * static, color=colour, ls=":", lw=0.9)
        lowest = min(lowest, float(np.nanmin(tension)))
    # The levels' styles, once (each run's in its colour).
    ax.plot([], [], "k--", lw=0.8, label="static: the submerged weight below the top")
    ax.plot([], [], "k:", lw=0.9, label=f"slack line: {SLACK_FRACTION:.0%} of static (DNV-RP-H103)")
    tolerance = trajectories[0].physics.slack.compression_tolerance
    if lowest < 0.5 * SLACK_FRACTION * np.nanmax(np.abs(trajectories[0].top_tension)):
        ax.axhline(0.0, color="k", lw=0.8)
    if lowest < 0:
        ax.axhline(-1e-3 * tolerance, color="r", ls="--", lw=1.0,
                   label=f"a push of {significant(1e-3 * tolerance)} kN fails the run")  # fmt: skip
    ax.set_xlabel("t [s]")
    ax.set_ylabel("top tension [kN]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1))  # beside the curves
    ax.set_title(run_title("top tension against its static value and the slack line",
                           [t.scene_name for t in trajectories], labels))  # fmt: skip
    return finish_figure(fig, path)


def _shares(tension: np.ndarray, static: np.ndarray) -> str:
    """The least and largest tension, in kN and as shares of static at the same instant."""
    with np.errstate(invalid="ignore", divide="ignore"):
        share = tension / static
    low, high = int(np.nanargmin(tension)), int(np.nanargmax(tension))
    return (
        f"least {significant(1e-3 * tension[low])} kN ({share[low]:.0%} of static), largest "
        f"{significant(1e-3 * tension[high])} kN ({share[high]:.0%})"
    )
