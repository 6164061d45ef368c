"""The ``cable-ocp`` script: the command line, interruptible from its first instant.

Importing the command line takes about two seconds (CasADi, xarray, the package); this module
imports nothing heavy, so that a Ctrl-C in those seconds ends the process as one during a run
does: one line ``cable-ocp: interrupted`` on stderr and exit 130, never a traceback.

SIGTERM is handled as SIGINT, by whatever handles SIGINT at that moment (a result file's write
holds it to its end, a solve turns it into an interrupt, elsewhere it is a KeyboardInterrupt): the
folder lock is released and the scratch folders removed as after a Ctrl-C, and the exit code is
143 (128 + SIGTERM) where a Ctrl-C gives 130.

``cable-ocp bench`` runs numpy's BLAS on one thread (set here, before numpy loads; a thread count
the user sets wins): its wall times then do not depend on how many cores the machine's BLAS
takes, and two benchmarks side by side do not share them (the grid bench's figures in the README
were measured so).
"""

from __future__ import annotations

import os
import signal
import sys
from collections.abc import MutableMapping

# The BLAS libraries' thread counts (OpenBLAS, as numpy's wheels bundle it; OpenMP; MKL).
BLAS_THREADS = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")

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
    one_blas_thread_for_bench(sys.argv[1:] if argv is None else argv, os.environ)
    try:
        from cable_ocp.cli import main as command_line

        code = command_line(argv)
    except KeyboardInterrupt:
        print("cable-ocp: interrupted", file=sys.stderr)
        code = INTERRUPTED
    finally:
        signal.signal(signal.SIGTERM, previous)
    return TERMINATED if terminated and code == INTERRUPTED else code


def one_blas_thread_for_bench(argv: list[str], environ: MutableMapping[str, str]) -> None:
    """Set :data:`BLAS_THREADS` to 1 in ``environ`` for ``cable-ocp bench`` (module docstring).

    Only the ones not set already; other commands are left alone (a solve may use both cores).
    """
    if argv and argv[0] == "bench":
        for name in BLAS_THREADS:
            environ.setdefault(name, "1")
