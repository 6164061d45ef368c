"""A run's results folder, as ``simulate`` and ``replay`` write it: trajectory, figures, summary."""

from __future__ import annotations

from pathlib import Path

from cable_ocp.cli.exits import SUCCESS, failed
from cable_ocp.cli.files import results_folder
from cable_ocp.scene.output import json_text

# Units of the figures a command adds to a run's summary.json (the run's own: its summary()).
EXTRA_UNITS = {"saved_omega": "m", "locked_omega": "m", "retimed": "1"}


def write_run(
    command: str, trajectory, scene, out: Path, animate: bool, extra: dict | None = None
) -> int:
    """A run's trajectory, figures and summary.json in ``out``; the summary printed.

    Parameters
    ----------
    command : str
        The command that ran it, as its messages name it.
    trajectory : Trajectory or LineTrajectory
        The run.
    scene : Scene
        The scene it ran (its seabed and winch range in the figures).
    out : Path
        The results folder.
    animate : bool
        Also write ``animation.gif``.
    extra : dict, optional
        Figures the command adds to the summary, each named in :data:`EXTRA_UNITS`.

    Returns
    -------
    int
        The exit code: 3 when the run fails its physics check (a rope that pushes, an end under
        the seabed: :attr:`~cable_ocp.simulation.trajectory.Trajectory.physics`), written all the
        same so that it can be looked at; else 0.
    """
    from cable_ocp import plots
    from cable_ocp.plots.tension import tension_against_static

    seabed = scene.seabed
    with results_folder(out) as folder:
        trajectory.save(folder / "trajectory")
        if animate:
            plots.animate(trajectory, folder / "animation.gif", seabed.clearance)
        plots.end_trajectory(trajectory, path=folder / "end_trajectory.png")
        plots.clearance(trajectory, seabed.clearance, path=folder / "clearance.png",
                        minimum_clearance=seabed.minimum_clearance)  # fmt: skip
        plots.cable_shapes(trajectory, seabed=seabed, path=folder / "cable_shapes.png")
        plots.winch_angle(trajectory, bounds=(scene.winch.angle_min, scene.winch.angle_max),
                          path=folder / "winch_angle.png")  # fmt: skip
        tension_against_static(trajectory, path=folder / "tension.png")
        if scene.winch.line is not None:  # a line paid out by elements: n over time
            plots.line_run(trajectory, path=folder / "line_run.png")
        figures = trajectory.summary()
        units = {**figures.pop("units"), **{name: EXTRA_UNITS[name] for name in extra or {}}}
        summary = {**figures, "scene": scene.name, **(extra or {}), "units": units}
        (folder / "summary.json").write_text(json_text(summary))
    print(json_text(summary))
    print(f"results and figures written to {out.resolve()}")
    if not trajectory.success:
        return failed(command, f"error: the run is not physical: {trajectory.status}")
    return SUCCESS
