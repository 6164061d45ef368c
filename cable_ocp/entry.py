"""The ``cable-ocp`` script: the command line, interruptible from its first instant.

Importing the command line takes about two seconds (CasADi, xarray, the package); this module
imports nothing heavy, so that a Ctrl-C in those seconds ends the process as one during a run
does: one line ``cable-ocp: interrupted`` on stderr and exit 130, never a traceback.

SIGTERM is handled as SIGINT, by whatever handles SIGINT at that moment (a result file's write
holds it to its end, a solve turns it into an interrupt, elsewhere it is a KeyboardInterrupt): the
folder lock is released and the scratch folders removed as after a Ctrl-C, and the exit code is
143 (128 + SIGTERM) where a Ctrl-C gives 130.
"""

from __future__ import annotations

import signal
import sys

# Exit codes of an interrupted command, 128 + the signal's number as a shell reports it.
INTERRUPTED = 128 + signal.SIGINT  # 130
TERMINATED = 128 + signal.SIGTERM  # 143


def main(argv: list[str] | None = None) -> int:
    """Run ``cable-ocp`` with ``argv`` (default: the process's arguments); the exit code.

    Parameters
    ----------
    argv : list of str, optional
        The arguments after ``cable-ocp``.

    Returns
    -------
    int
        :func:`cable_ocp.cli.main`'s exit code, 130 after a Ctrl-C during the imports, and 143
        instead of 130 when the interrupt was a SIGTERM.
    """
    terminated: list[int] = []

    def terminate(number: int, frame) -> None:
        terminated.append(number)
        handler = signal.getsignal(signal.SIGINT)
        if not callable(handler):  # SIGINT ignored (a background job): still an interrupt
            raise KeyboardInterrupt
        handler(signal.SIGINT, frame)

    previous = signal.signal(signal.SIGTERM, terminate)
    try:
        from cable_ocp.cli import main as command_line

        code = command_line(argv)
    except KeyboardInterrupt:
        print("cable-ocp: interrupted", file=sys.stderr)
        code = INTERRUPTED
    finally:
        signal.signal(signal.SIGTERM, previous)
    return TERMINATED if terminated and code == INTERRUPTED else code
