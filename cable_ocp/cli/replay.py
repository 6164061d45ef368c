"""``cable-ocp replay RESULT --out DIR``: a saved winch driving its scene, or a changed one."""

from __future__ import annotations

import argparse
from pathlib import Path

from cable_ocp.cli.arguments import (
    INTERPRETED_HELP,
    OUT_HELP,
    add_animate,
    add_command,
    add_quiet,
    add_set,
    parse_overrides,
)
from cable_ocp.cli.run_folder import write_run
from cable_ocp.drive.winch import RETIMES, replayed_duration

REPLAYABLE = (
    "what optimize or mpc saved (result.nc, mpc.nc; lower's hover_*.nc and hold.nc), or a "
    "landing plan, landing or hold that the API saved"
)


def add_replay_command(commands) -> None:
    """Add ``replay`` to the subparsers of ``cable-ocp``."""
    parser = add_command(
        commands, "replay",
        "drive a scene by a saved optimum or closed loop (its own scene, or changed by --set)",
        scene=False,
    )  # fmt: skip
    parser.add_argument("result", type=Path, help=f"a folder or file holding {REPLAYABLE}")
    parser.add_argument("--out", type=Path, required=True, help=OUT_HELP)
    add_set(parser, "model.elements=60", "a field of the saved scene")
    parser.add_argument(
        "--retime", choices=list(RETIMES),
        help="on a scene of another numerics.duration (--set): "
        + "; ".join(f"{name}: {text}" for name, text in RETIMES.items())
        + " (default: such a replay is refused)",
    )  # fmt: skip
    add_quiet(parser)
    parser.add_argument("--interpreted", action="store_true", help=INTERPRETED_HELP)
    add_animate(parser)
    parser.set_defaults(run=run_replay_command)


def run_replay_command(args: argparse.Namespace) -> int:
    """Run ``cable-ocp replay``; 3 when the run is not physical, 0 otherwise.

    The summary adds ``saved_omega``, the Omega the result was saved with (m), where it states
    one. A replay on another duration is refused unless ``--retime`` says how, before any work;
    a retimed one prints what the retiming did.
    """
    from cable_ocp.lowering.results import load_result
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
    kind = type(result).__name__
    if not hasattr(result, "winch_profile"):  # a run: its winch is not kept to drive
        raise ValueError(
            f"{args.result}: holds a {kind}, a run whose winch is not kept as a profile to "
            f"drive; replay takes {REPLAYABLE}, whose winch it drives (a run is made again by "
            "cable-ocp simulate on its scene)"
        )
    if args.retime is not None and not hasattr(result, "retimed"):
        raise ValueError(
            f"--retime {args.retime}: a {kind} replays in its own time on any duration (held "
            "after its end); leave --retime out"
        )
    scene = result.scene.updated(parse_overrides(args.set)) if args.set else result.scene
    own = getattr(result, "duration", None)  # None: the winch keeps its own time
    replayed_duration(own, scene.numerics.duration, args.retime, "--retime {}")
    winch = result if args.retime is None else result.retimed(args.retime)
    with stage(f"replay {scene.name}", scene.numerics.duration, quiet=args.quiet):
        trajectory = simulate(scene, winch=winch, quiet=args.quiet, compiled=not args.interpreted)
    saved = {"saved_omega": result.omega} if hasattr(result, "omega") else {}
    if args.retime is not None and winch.note(scene):
        print(f"note: {winch.note(scene)}")
        saved["retimed"] = winch.note(scene)
    return write_run("replay", trajectory, scene, Path(args.out), args.animate, saved)
