"""The last step of a study's chart: laid out, and saved and closed when it has a file."""

from __future__ import annotations

from pathlib import Path

CHART_DPI = 120


def finished_chart(fig, path: Path | str | None = None):
    """Lay out a pyplot figure; with ``path``, save it there and close it.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        A figure made by ``matplotlib.pyplot`` (closed once saved).
    path : Path or str, optional
        File to save the chart to, at :data:`CHART_DPI`; none: the figure stays open.

    Returns
    -------
    matplotlib.figure.Figure
        ``fig``, for a notebook to show when it was not saved.
    """
    import matplotlib.pyplot as plt

    fig.tight_layout()
    if path is not None:
        fig.savefig(path, dpi=CHART_DPI)
        plt.close(fig)
    return fig
