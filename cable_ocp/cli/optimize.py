"""``cable-ocp optimize SCENE --out DIR``: the optimal winch, verified, beside a locked winch."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from cable_ocp.cli.arguments import (
    Renamed,
    add_animate,
    add_command,
    integer,
    scene_from,
)
from cable_ocp.cli.exits import SUCCESS, failed, one_line
from cable_ocp.cli.files import results_folder
from cable_ocp.cli.optimiser_options import (
    add_optimiser_options,
    check_step,
    elapsed,
    optimize_settings,
)
from cable_ocp.cli.run_folder import EXTRA_UNITS


def add_optimize_command(commands) -> None:
    """Add ``optimize`` to the subparsers of ``cable-ocp``."""
    parser = add_command(commands, "optimize", "optimise the winch angle of a scene")
    parser.add_argument(
        "--method", action=Renamed,
        now="--solver: --solver nelder-mead is the paper's method; shooting is --solver "
        "gauss-newton (the default) or --solver ipopt",
    )  # fmt: skip
    parser.add_argument(
        "--refinements", type=integer(0, 100),
        help="model-correction solves of a shooting solver (default: optimize()'s)",
    )  # fmt: skip
    add_optimiser_options(parser)
    add_animate(parser)
    parser.set_defaults(run=run_optimize_command)


def _locked_reference(scene):
    """The locked winch's run for comparison, or None and why it failed.

    Only the verified profile must stay sound: a locked run that blows up or leaves the
    bathymetry grid is reported beside the result, never in its place.
    """
    from cable_ocp.simulation.integrate import SimulationError
    from cable_ocp.simulation.run import simulate

    try:
        return simulate(scene, quiet=True), ""
    except SimulationError as error:
        return None, f"the locked reference run failed ({one_line(error)})"


def run_optimize_command(args: argparse.Namespace) -> int:
    """Run ``cable-ocp optimize``; 3 when the optimiser fails, 0 otherwise."""
    from cable_ocp import plots
    from cable_ocp.cli.exports import winch_csv
    from cable_ocp.control.optimization import optimize
    from cable_ocp.plots.drum_limits import drum_use
    from cable_ocp.plots.tension import tension_against_static
    from cable_ocp.scene.output import json_text

    scene = scene_from(args)
    check_step(scene, args.step)
    output = {"quiet": args.quiet, "verbose": args.verbose, "refinements": args.refinements}
    result = optimize(scene, settings=optimize_settings(args), **output)
    locked, locked_failure = _locked_reference(scene)
    seabed, bounds = scene.seabed, (scene.winch.angle_min, scene.winch.angle_max)
    runs = [("locked winch", locked), (f"optimised ({result.solver})", result.trajectory)]
    runs = [(label, run) for label, run in runs if run is not None]
    summary = {"scene": scene.name, **result.summary(),
               "locked_omega": locked.omega if locked is not None else float("nan")}  # fmt: skip
    summary["units"] = {**summary["units"], "locked_omega": EXTRA_UNITS["locked_omega"]}
    with results_folder(args.out) as folder:
        result.save(folder)
        (folder / "summary.json").write_text(json_text(summary))
        if result.trajectory is not None:
            (folder / "winch.csv").write_text(winch_csv(result.trajectory, scene))
        if runs:
            labels, pair = [label for label, _ in runs], [run for _, run in runs]
            plots.end_trajectory(pair, labels, path=folder / "end_trajectory.png")
            plots.clearance(pair, seabed.clearance, labels, folder / "clearance.png",
                            seabed.minimum_clearance)  # fmt: skip
            plots.winch_angle(pair, labels, bounds, path=folder / "winch_angle.png")
            tension_against_static(pair, labels, folder / "tension.png")
            if result.trajectory is not None:  # the optimum's drum (the locked one stands still)
                drum_use(result, path=folder / "drum.png")
            plots.cable_shapes(pair[-1], seabed=seabed, path=folder / "cable_shapes.png")
            if args.animate:
                plots.animate(pair[-1], folder / "animation.gif", seabed.clearance)
    n = scene.model.elements
    omega = (
        f"Omega = {result.omega:.3g} m verified on n = {n}"
        if math.isfinite(result.omega)
        else f"Omega not verified on n = {n}"
    )
    locked_omega = "no locked run" if locked is None else f"locked: {locked.omega:.3f} m"
    print(
        f"{result.solver}: success = {result.success} ({result.status}); {omega} "
        f"({locked_omega}); iterations {result.iterations}, evaluations "
        f"{result.evaluations}; optimize() took {result.wall_time:.1f} s (build "
        f"{result.build_time:.1f} s, solver {result.solve_time:.1f} s of which functions "
        f"{result.function_time:.1f} s), the whole command {elapsed(args):.1f} s (with the "
        "imports, the locked winch's run and the figures)"
    )
    if result.notes:
        print(f"note: {result.notes}")
    if locked_failure:
        print(f"note: {locked_failure}; the comparison with the locked winch is left out")
    print(f"results and figures written to {Path(args.out).resolve()}")
    if not result.success:
        return failed("optimize", f"the optimiser failed: {result.status}")
    return SUCCESS
