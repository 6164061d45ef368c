"""``cable-ocp replay RESULT --out DIR``: a saved optimum driving its scene, or a changed one."""

from __future__ import annotations

import argparse
from pathlib import Path

from cable_ocp.cli.arguments import (
    ANIMATE_HELP,
    INTERPRETED_HELP,
    OUT_HELP,
    add_command,
    add_set,
    parse_overrides,
)
from cable_ocp.cli.run_folder import write_run


def add_replay_command(commands) -> None:
    """Add ``replay`` to the subparsers of ``cable-ocp``."""
    parser = add_command(
        commands, "replay",
        "drive a scene by a saved optimum (on its own scene, or changed by --set)", scene=False,
    )  # fmt: skip
    parser.add_argument("result", type=Path,
                        help="a folder that optimize wrote (or its result.nc)")  # fmt: skip
    parser.add_argument("--out", type=Path, required=True, help=OUT_HELP)
    add_set(parser, "model.elements=60", "a field of the saved scene")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    parser.add_argument("--interpreted", action="store_true", help=INTERPRETED_HELP)
    parser.add_argument("--animate", action="store_true", help=ANIMATE_HELP)
    parser.set_defaults(run=run_replay_command)


def run_replay_command(args: argparse.Namespace) -> int:
    """Run ``cable-ocp replay``; 3 when the run is not physical, 0 otherwise.

    The summary adds ``saved_omega``, the Omega the optimum was saved with (m).
    """
    from cable_ocp.control.optimization import OcpResult
    from cable_ocp.control.results import load_result
    from cable_ocp.simulation.progress import stage
    from cable_ocp.simulation.run import simulate

    source = args.result.expanduser().resolve()
    source = source.parent if source.suffix == ".nc" else source
    out = args.out.expanduser().resolve()
    if out == source or out in source.parents:
        raise ValueError(
            f"--out {args.out}: is the folder replay reads ({source}), which the replay's run "
            "would replace; give another folder; nothing was written"
        )
    result = load_result(args.result)
    if not isinstance(result, OcpResult):
        raise ValueError(
            f"{args.result}: holds a {type(result).__name__}; replay takes what optimize saved "
            "(result.nc), whose profile it drives"
        )
    scene = result.scene.updated(parse_overrides(args.set)) if args.set else result.scene
    with stage(f"replay {scene.name}", scene.numerics.duration, quiet=args.quiet):
        trajectory = simulate(scene, winch=result, quiet=args.quiet, compiled=not args.interpreted)
    return write_run(
        "replay", trajectory, scene, Path(args.out), args.animate, {"saved_omega": result.omega}
    )
