"""A user's Ctrl-C during a solve leaves it as the KeyboardInterrupt it was.

CasADi checks for interrupts inside its calls and turns one into an error or a return status
(IPOPT's ``User_Requested_Stop``, or ``NonIpopt_Exception_Thrown``; a plain Function call or a
QP swallows it), so a solve watches SIGINT itself: :func:`keeping_interrupts` records the signal,
re-raises it as KeyboardInterrupt when the solve ends (or turns the RuntimeError it caused into
one, or the SystemError of a CasADi result returned with the interrupt still set), and
:func:`check` lets a solver's own loop stop at once. The handler is only watched from the main
thread (a Dask worker's solve cannot be interrupted this way anyway). The command line hands a
SIGTERM to SIGINT's handler of the moment (:mod:`cable_ocp.entry`), so it is watched the same way.

A test interrupts at a known point, never after a delay: with ``CABLE_OCP_INTERRUPT_AT=POINT``
in its environment, the process sends itself one SIGINT the first time it passes
:func:`interrupt_here` ``(POINT)``: ``"check"`` (each :func:`check`, e.g. a Gauss-Newton
iteration) or ``"reference run"`` (a closed loop's reference run, after the loop).
"""

from __future__ import annotations

import os
import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager

INTERRUPT_AT = "CABLE_OCP_INTERRUPT_AT"


@contextmanager
def keeping_interrupts() -> Iterator[list[int]]:
    """Watch SIGINT over a block; yields the list of signals seen (see the module docstring)."""
    seen: list[int] = []
    previous = signal.getsignal(signal.SIGINT)
    watched = threading.current_thread() is threading.main_thread() and callable(previous)

    def watch(number, frame):
        seen.append(number)
        previous(number, frame)

    if watched:
        signal.signal(signal.SIGINT, watch)
    try:
        yield seen
    except (RuntimeError, SystemError):
        if seen:
            raise KeyboardInterrupt from None
        raise
    finally:
        if watched:
            signal.signal(signal.SIGINT, previous)
    check(seen)


def check(seen: list[int]) -> None:
    """Raise KeyboardInterrupt if a SIGINT was seen (CasADi may have swallowed it)."""
    interrupt_here("check")
    if seen:
        raise KeyboardInterrupt


def interrupt_here(point: str) -> None:
    """Send this process a SIGINT if ``$CABLE_OCP_INTERRUPT_AT`` names ``point`` (once; tests)."""
    if os.environ.get(INTERRUPT_AT) == point:
        del os.environ[INTERRUPT_AT]
        signal.raise_signal(signal.SIGINT)
