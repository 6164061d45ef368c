"""Figures of a lowering (matplotlib), by the rules of :mod:`cable_ocp.plots`.

:func:`landing` draws a run of a ``[lowering]`` scene against its targets: the end's height above
the seabed with the reference descent (or a landing's reference), the landing's tolerance and the
hold band with the vessel's heave beside them, and the top tension between its limits. The figure
returns; with ``path`` it is saved there and closed.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator

from cable_ocp.plots import finish_figure, run_title, significant
from cable_ocp.simulation.landing_reference import is_landing, reference_error
from cable_ocp.simulation.line_trajectory import LineTrajectory
from cable_ocp.simulation.seabed import clearance, clearance_reference
from cable_ocp.simulation.trajectory import Trajectory

HEAVE_SHOWN = 1e-3  # m: a top that moves less in the last tenth is drawn without its heave


def landing(
    run: Trajectory | LineTrajectory,
    descent=None,
    report=None,
    path: str | Path | None = None,
    label: str = "simulated",
) -> Figure:
    """Height above the seabed and top tension of a landing run, against the lowering's limits.

    Parameters
    ----------
    run : Trajectory or LineTrajectory
        A run of a scene with ``[lowering]``.
    descent : ReferenceDescent, optional
        Drawn as the height it means (the start's height less the line paid out: the vertical
        drop). A landing from a hover (fixed ``n``) draws its own reference
        (:mod:`~cable_ocp.simulation.landing_reference`).
    report : LandingReport, optional
        Its failed checks are named in the title.
    path : str or Path, optional
        Where to save the figure (closed after).
    label : str
        What the run is (``simulated``, ``optimised (ipopt)``, ...).
    """
    scene = run.scene
    lowering = scene.lowering
    time, end = run.time, run.end
    height = clearance(scene.seabed, end, clearance_reference(scene.seabed, end[0]))
    fig, (upper, middle, lower) = plt.subplots(3, 1, figsize=(10, 9.5))
    upper.sharex(lower)  # the middle panel spans the landing's last tenth and the hold only
    upper.tick_params(labelbottom=False)
    upper.plot(time, height, label=label)
    if descent is not None:
        line = descent.line_out(time)[0]
        upper.plot(time, height[0] - (line - line[0]), "k--", lw=1,
                   label="reference descent (vertical drop)")  # fmt: skip
    elif is_landing(scene):
        start = height[0] - scene.seabed.clearance
        reference = height[0] + reference_error(scene, time, start) - start
        upper.plot(time, reference, "k--", lw=1, label="landing reference")
    upper.axhline(
        lowering.height, color="C2", lw=1, label=f"target {significant(lowering.height)} m"
    )
    for ax in (upper, middle, lower):
        ax.axvline(lowering.land_time, color="0.5", ls=":", lw=1)
    upper.plot([], [], color="0.5", ls=":", lw=1,
               label=f"landing time {significant(lowering.land_time)} s")  # fmt: skip
    # The last tenth of the descent and the hold, to the scale of the landing's tolerances (of
    # the run, where a closed loop stopped before the landing).
    near = time >= min(0.9 * lowering.land_time, time[0] + 0.9 * (time[-1] - time[0]))
    hold = time >= lowering.land_time
    middle.plot(time[near], height[near] - lowering.height, label=label)
    middle.fill_between(
        time[hold], -lowering.hold_band, lowering.hold_band, color="C2", alpha=0.25,
        label=f"hold band +/- {significant(lowering.hold_band)} m",
    )  # fmt: skip
    tolerance = lowering.height_tolerance
    middle.errorbar([lowering.land_time], [0.0], yerr=[tolerance], color="C3", capsize=6,
                    label=f"landing +/- {significant(tolerance)} m")  # fmt: skip
    scale = 4 * max(lowering.hold_band, lowering.height_tolerance)
    middle.set_ylim(-scale, scale)
    heave = run.top[:, 2]
    on_top = middle  # the axes drawn last, which holds the legend so that nothing covers it
    # The vessel's heave on its own scale: what the load is spared (the top joint's bond
    # residual, 1e-6 m, is no heave).
    if np.ptp(heave[near]) > HEAVE_SHOWN:
        on_top = middle.twinx()
        swell = heave[near] - heave[near].mean()
        on_top.plot(time[near], swell, color="0.6", lw=0.8, label="vessel heave (right axis)")
        reach = np.abs(swell).max()
        on_top.set_ylim(-1.1 * reach, 3.3 * reach)  # the lower half: the legend keeps the upper
        on_top.set_ylabel("vessel heave at the winch [m]", color="0.4")
    middle.set_ylabel("end above the target [m]")
    if time[-1] > time[near][0]:  # a plant that failed in its first step has one sample
        middle.set_xlim(time[near][0], time[-1])
    middle.set_xlabel("t [s]")
    shown = [middle] if on_top is middle else [middle, on_top]
    handles = [h for ax in shown for h in ax.get_legend_handles_labels()[0]]
    on_top.legend(handles=handles, fontsize=8, loc="upper right", ncol=2)
    upper.set_ylabel("end above the seabed [m]")
    upper.legend(fontsize=8, loc="upper right")
    lower.plot(time, 1e-3 * run.top_tension, label="top tension")
    lower.axhline(1e-3 * lowering.tension_min, color="C3", ls="--", lw=1,
                  label=f"tension_min {significant(1e-3 * lowering.tension_min)} kN")  # fmt: skip
    most = lowering.tension_max
    if most is not None:
        lower.axhline(1e-3 * most, color="C3", ls="-.", lw=1,
                      label=f"tension_max {significant(1e-3 * most)} kN")  # fmt: skip
    lower.set_xlabel("t [s]")
    lower.set_ylabel("top tension [kN]")
    lower.legend(fontsize=8, loc="lower right")
    if isinstance(run, LineTrajectory):
        count = lower.twinx()
        count.plot(time, run.element_count, color="0.6", lw=0.8)
        count.set_ylabel("elements n [count]", color="0.4")
        count.yaxis.set_major_locator(MaxNLocator(integer=True))
    verdict = "" if report is None else (
        ", every check passed" if report.passed
        else ", failed: " + ", ".join(check.name for check in report.failures)
    )  # fmt: skip
    fig.suptitle(run_title(f"landing{verdict}", [run.scene_name], [label]), fontsize=10)
    if time[-1] > time[0]:
        upper.set_xlim(time[0], time[-1])
    return finish_figure(fig, path)
