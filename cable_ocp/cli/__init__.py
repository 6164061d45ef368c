"""The command line, ``cable-ocp COMMAND``.

Commands: simulate, replay, optimize, compare, mpc, lower, sweep, learn, validate, study, bench;
``cable-ocp scenes`` lists the bundled scenes, ``cable-ocp schema [KEY]`` the fields of a scene;
``cable-ocp COMMAND --help`` tells what each command does.

Every expected failure is one line ``cable-ocp COMMAND: error: ...`` on stderr and an exit code,
the same for every command (``cable_ocp.cli.exits``):
"""

from __future__ import annotations

import argparse
import os
import sys
import time

from cable_ocp.cli.bench import add_bench_command
from cable_ocp.cli.compare import add_compare_command
from cable_ocp.cli.exits import BROKEN_PIPE, INTERRUPTED, described, exit_code, one_line
from cable_ocp.cli.files import check_replaceable
from cable_ocp.cli.learn import add_learn_command
from cable_ocp.cli.lower import add_lower_command
from cable_ocp.cli.mpc import add_mpc_command
from cable_ocp.cli.optimize import add_optimize_command
from cable_ocp.cli.reference import add_reference_commands
from cable_ocp.cli.replay import add_replay_command
from cable_ocp.cli.simulate import add_simulate_command
from cable_ocp.cli.study import add_study_command
from cable_ocp.cli.sweep import add_sweep_command
from cable_ocp.cli.validate import add_validate_command
from cable_ocp.scene.output import claimed_target

# In the order of the help; each module adds its command(s) to the subparsers.
COMMANDS = (
    add_simulate_command,
    add_replay_command,
    add_validate_command,
    add_optimize_command,
    add_compare_command,
    add_mpc_command,
    add_lower_command,
    add_sweep_command,
    add_learn_command,
    add_reference_commands,
    add_study_command,
    add_bench_command,
)


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of ``cable-ocp``."""
    # The module docstring is reStructuredText; the terminal gets it without the markup.
    parser = argparse.ArgumentParser(
        prog="cable-ocp",
        description=__doc__.replace("``", "").replace(":mod:`cable_ocp.cli.exits`", "")
        + "\n"
        + described(),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    commands = parser.add_subparsers(dest="command", required=True)
    for add in COMMANDS:
        add(commands)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``cable-ocp``; returns the exit code (:mod:`cable_ocp.cli.exits`)."""
    started = time.perf_counter()
    try:
        args = build_parser().parse_args(argv)
    except SystemExit as exit_:  # argparse: --help (0) or a usage error (2), already printed
        return exit_.code if isinstance(exit_.code, int) else 0
    prefix = f"cable-ocp {args.command}"
    args.started = started
    try:
        # Before any work, so a bad or busy --out costs nothing, and held to the last write; a
        # sweep folder is resumed, and cable_ocp.sweep checks and locks it as its own.
        out = getattr(args, "out", None) if args.command != "sweep" else None
        if out is not None:
            check_replaceable(out)
        with claimed_target(out):
            return args.run(args)
    except (KeyboardInterrupt, ValueError, OverflowError, RuntimeError, OSError) as error:
        code = exit_code(error)
        if code == INTERRUPTED:
            print(f"{prefix}: interrupted", file=sys.stderr)
        elif code == BROKEN_PIPE:  # the output's reader closed it (| head): stop without a word
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        else:
            print(f"{prefix}: error: {one_line(error)}", file=sys.stderr)
        return code
