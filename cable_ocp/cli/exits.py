"""The exit codes of ``cable-ocp``, the same for every command, and the one line of a failure.

=====  ===============================================================================
code   meaning
=====  ===============================================================================
0      success
1      the file system failed (a full disk, a file-size limit, a folder not renamed)
2      bad input, refused before any work: an argument, a scene or sweep file, a results
       folder that must not be written, a scene with no equilibrium, a bathymetry grid
       that the end starts under or leaves (``OffGridError``: extend the grid)
3      the work failed: an optimiser, the closed loop, a landing or hold, a sweep case or
       its engine, a run that is not physical (its results written all the same), or a
       run that blew up (``SimulationError``: nothing written)
130    interrupted (Ctrl-C)
141    the output's reader closed it (``| head``)
143    terminated (SIGTERM, handled as an interrupt; the script's :mod:`cable_ocp.entry`
       says which signal it was, and gives 130 for a Ctrl-C during the imports)
=====  ===============================================================================
"""

from __future__ import annotations

import sys

SUCCESS = 0
FILE_SYSTEM = 1
BAD_INPUT = 2
FAILED = 3
INTERRUPTED = 130
BROKEN_PIPE = 141


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
