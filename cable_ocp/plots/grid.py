"""The speed-accuracy chart of the control grid: Omega against the number of parameters."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
from matplotlib.figure import Figure
from matplotlib.ticker import NullFormatter, ScalarFormatter

from cable_ocp.plots.figure import finish_figure

# How each kind of grid is drawn: a line through the uniform grids, markers for the others.
STYLES = {
    "uniform": {"marker": "o", "ls": "-", "label": "uniform Hermite grids"},
    "adaptive": {"marker": "*", "ls": "none", "ms": 12, "label": "adaptive grid"},
    "spline": {"marker": "s", "ls": "none", "label": "the paper's knots (spline)"},
}


def omega_against_parameters(points: dict, path: str | Path | None = None) -> Figure:
    """Omega (m) against the number of winch parameters, one panel per scene.

    Parameters
    ----------
    points : dict
        Scene name -> points ``{"kind", "label", "parameters", "omega"}``
        (:func:`cable_ocp.studies.bench_grid.chart_points`); ``kind`` is ``"uniform"``,
        ``"adaptive"`` or ``"spline"``.
    path : path-like, optional
        Where to save the figure.
    """
    fig, axes = plt.subplots(1, len(points), figsize=(4.6 * len(points), 4.2), squeeze=False)
    for ax, (name, scene_points) in zip(axes[0], points.items(), strict=True):
        for kind, style in STYLES.items():
            chosen = sorted(
                (p for p in scene_points if p["kind"] == kind), key=lambda p: p["parameters"]
            )
            if chosen:
                ax.plot([p["parameters"] for p in chosen], [p["omega"] for p in chosen], **style)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.xaxis.set_major_formatter(ScalarFormatter())
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.set_title(name, fontsize=9)
        ax.set_xlabel("winch parameters")
        ax.set_ylabel("Omega [m] (verified on the scene's model)")
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=8)
    fig.suptitle("the control grid's speed-accuracy chart (issue 43)")
    return finish_figure(fig, path)
