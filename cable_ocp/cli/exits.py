"""The exit codes of ``cable-ocp``, the same for every command, and the one line of a failure.

:data:`MEANINGS` states each code; ``cable-ocp --help`` prints them, :func:`exit_code` maps an
exception that ends a command to its code.
"""

from __future__ import annotations

import sys
import textwrap

SUCCESS = 0
FILE_SYSTEM = 1
BAD_INPUT = 2
FAILED = 3
INTERRUPTED = 130
BROKEN_PIPE = 141
TERMINATED = 143  # given by the script, cable_ocp.entry, for a SIGTERM

MEANINGS = {
    SUCCESS: "success",
    BAD_INPUT: "bad input, refused before any work: an argument, a scene or sweep file, a "
    "results folder that must not be written (one inside a read-only folder included), a scene "
    "with no equilibrium, a bathymetry grid that the end starts under or leaves",
    FAILED: "the work failed: an optimiser, the closed loop, a landing or hold, a sweep case or "
    "its Dask engine, a run that is not physical (a rope that pushes, an end under the seabed: "
    "its results written all the same), a run that blew up (nothing written)",
    FILE_SYSTEM: "the file system failed (a full disk, a file-size limit, a folder not renamed)",
    INTERRUPTED: "interrupted (Ctrl-C)",
    TERMINATED: "terminated (SIGTERM), cleaned up as after a Ctrl-C",
    BROKEN_PIPE: "the output's reader closed it (| head)",
}


def described(width: int = 96) -> str:
    """The exit codes and their meanings as the help prints them, lines of ``width`` at most."""
    return "\n".join(
        textwrap.fill(meaning, width, initial_indent=f"{code:>5}  ", subsequent_indent=" " * 7)
        for code, meaning in MEANINGS.items()
    )


def exit_code(error: BaseException) -> int | None:
    """The exit code of an exception that ended a command (None: not an expected failure).

    The first match counts: a ``BrokenPipeError`` is an ``OSError`` that is no failure of the
    file system, an ``OffGridError`` a ``SimulationError`` whose cause is the scene's grid. A
    ``RuntimeError`` other than a ``SimulationError`` is an ``EquilibriumError`` (a scene no cable
    can hang in) or netCDF's refusal of a damaged file: bad input.
    """
    for kinds, code in ((KeyboardInterrupt, INTERRUPTED), (BrokenPipeError, BROKEN_PIPE),
                        (OSError, FILE_SYSTEM)):  # fmt: skip
        if isinstance(error, kinds):
            return code
    if not isinstance(error, (ValueError, OverflowError, RuntimeError)):
        return None
    # Only now: the simulation's modules import CasADi, which an interrupt may have stopped.
    from cable_ocp.simulation.integrate import SimulationError
    from cable_ocp.simulation.seabed import OffGridError

    if isinstance(error, SimulationError) and not isinstance(error, OffGridError):
        return FAILED
    return BAD_INPUT


def one_line(error: BaseException) -> str:
    """The error's message on one line (its type's name when it has none)."""
    return " ".join(str(error).split()) or type(error).__name__


def failed(command: str, why: str) -> int:
    """Print ``cable-ocp COMMAND: WHY`` on stderr; :data:`FAILED`, the work failed."""
    print(f"cable-ocp {command}: {why}", file=sys.stderr)
    return FAILED
