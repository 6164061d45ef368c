"""``cable-ocp simulate SCENE --out DIR``: one run of a scene, its figures and summary."""

from __future__ import annotations

import argparse
from pathlib import Path

from cable_ocp.cli.arguments import (
    INTERPRETED_HELP,
    add_animate,
    add_command,
    add_quiet,
    add_set,
    knot_angles,
    scene_from,
)
from cable_ocp.cli.run_folder import write_run

KNOTS_HELP = (
    "winch knot angles phi_1..phi_p in rad, comma-separated, p = winch.knots (write "
    "--knots=-1,0.5 when the first is negative): phi(0) = 0 is put before them, knot i sits at "
    "t = i T / p (T = numerics.duration), and the cubic spline through them starts at rest "
    "(zero rate; free at the end); phi > 0 pays out; default: the winch locked"
)


def add_simulate_command(commands) -> None:
    """Add ``simulate`` to the subparsers of ``cable-ocp``."""
    parser = add_command(commands, "simulate", "simulate a scene and write results and figures")
    parser.add_argument("--knots", type=knot_angles, help=KNOTS_HELP)
    add_set(parser, "model.elements=30")
    add_quiet(parser)
    parser.add_argument("--interpreted", action="store_true", help=INTERPRETED_HELP)
    add_animate(parser)
    parser.set_defaults(run=run_simulate_command)


def run_simulate_command(args: argparse.Namespace) -> int:
    """Run ``cable-ocp simulate``; 3 when the run is not physical, 0 otherwise."""
    from cable_ocp.simulation.progress import stage
    from cable_ocp.simulation.run import simulate

    scene = scene_from(args)
    knots = args.knots
    if knots is not None and len(knots) != scene.winch.knots:
        raise ValueError(
            f"--knots: {len(knots)} angles given; the scene has winch.knots = "
            f"{scene.winch.knots} (one angle phi_1..phi_p per knot, rad)"
        )
    # Compiled unless --interpreted: without a compiler or a writable cache, the interpreted
    # model runs after the same warning as the API's.
    with stage(f"simulate {scene.name}", scene.numerics.duration, quiet=args.quiet):
        trajectory = simulate(scene, winch=knots, quiet=args.quiet, compiled=not args.interpreted)
    return write_run("simulate", trajectory, scene, Path(args.out), args.animate)
