"""The one way a figure of :mod:`cable_ocp.plots` ends: laid out, then saved and closed with a path.

Its own module so that every figure module imports it without importing the package's
``__init__``, which imports some of them.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
from matplotlib.figure import Figure


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
