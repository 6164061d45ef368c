"""Charts of the study: error against CPU time, Omega against wall time."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.transforms import blended_transform_factory

from cable_ocp.studies.figures import CHART_DPI
from cable_ocp.studies.speed_accuracy.ocp_points import OcpPoint
from cable_ocp.studies.speed_accuracy.plan import TOLERANCES
from cable_ocp.studies.speed_accuracy.scenes import SceneStudy

MARKERS = "os^DvP*Xh<>"


def speed_chart(study: SceneStudy, path: Path) -> None:
    """Log-log error against CPU time: marker by n, filled compiled, open interpreted."""
    fig = Figure(figsize=(10, 5.5))
    ax = fig.subplots()
    counts = sorted({p.elements for p in study.points})
    for p in study.stable_points:
        marker = MARKERS[counts.index(p.elements) % len(MARKERS)]
        colour = "tab:red" if p.torsion else "tab:blue"
        face = colour if p.mode == "compiled" else "none"
        ax.loglog(p.cpu_time, p.error, marker, color=colour, mfc=face, ms=7, alpha=0.85)
    front = study.pareto()
    ax.loglog(
        [p.cpu_time for p in front], [p.error for p in front], "k-", lw=1, label="Pareto front"
    )
    for tolerance in TOLERANCES:
        ax.axhline(tolerance, color="gray", ls="--", lw=0.8)
        ax.annotate(
            f"{100 * tolerance:g} cm", (0.01, tolerance), xycoords=("axes fraction", "data"),
            ha="left", va="bottom", color="gray",
        )  # fmt: skip
    handles = [
        Line2D([], [], ls="", marker=MARKERS[k % len(MARKERS)], color="k", mfc="none")
        for k in range(len(counts))
    ]
    labels = [f"n = {n}" for n in counts]
    for colour, face, text in (
        ("tab:blue", "tab:blue", "no torsion, compiled"),
        ("tab:blue", "none", "no torsion, interpreted"),
        ("tab:red", "tab:red", "torsion, compiled"),
        ("tab:red", "none", "torsion, interpreted"),
    ):
        handles.append(Line2D([], [], ls="", marker="o", color=colour, mfc=face))
        labels.append(text)
    handles.append(Line2D([], [], color="k", lw=1))
    labels.append("Pareto front")
    ax.legend(handles, labels, fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    ax.set_xlabel("CPU time of the integration [s]")
    ax.set_ylabel(r"max$_t$ |r$_E$ - r$_{E,ref}$| [m]")
    ax.set_title(
        f"{study.scene_name}: {study.duration:g} s simulated, against n = "
        f"{study.reference.elements} DOP853 (rtol = atol = {study.reference.tolerance:g})"
    )
    ax.grid(alpha=0.3, which="both")
    fig.tight_layout()
    fig.savefig(path, dpi=CHART_DPI)


def ocp_chart(points: Sequence[OcpPoint], scene_name: str, path: Path) -> None:
    """Verified Omega against wall time; a failed solve is drawn as a cross.

    A solve whose last iterate cannot be simulated on the scene's model (Omega NaN) is drawn at
    the top edge.
    """
    fig = Figure(figsize=(8, 5))
    ax = fig.subplots()
    ax.set_xscale("log")
    ax.set_yscale("log")
    top_edge = blended_transform_factory(ax.transData, ax.transAxes)
    for k, p in enumerate(points):
        r = p.result
        state = "" if r.success else f" - FAILED: {r.status}"
        style = dict(color=f"C{k % 10}", marker="o" if r.success else "x", ms=9, mew=2, ls="")
        if np.isfinite(r.omega):
            ax.plot(r.wall_time, r.omega, label=f"{p.setting.label}{state}", **style)
        else:
            ax.plot(r.wall_time, 0.97, transform=top_edge, clip_on=False,
                    label=f"{p.setting.label}{state}", **style)  # fmt: skip
            ax.annotate("last iterate not simulable: no Omega", (r.wall_time, 0.97),
                        xycoords=top_edge, xytext=(-8, -4), textcoords="offset points",
                        ha="right", va="top", fontsize=7)  # fmt: skip
    ax.set_xlabel("wall time of the whole optimisation, verification included [s]")
    ax.set_ylabel(r"$\Omega$ verified on the scene's model [m]")
    ax.set_title(f"{scene_name}: optimal winch control, Omega (eq. 39) against wall time")
    ax.legend(fontsize=7, loc="best")
    ax.grid(alpha=0.3, which="both")
    fig.tight_layout()
    fig.savefig(path, dpi=CHART_DPI)
