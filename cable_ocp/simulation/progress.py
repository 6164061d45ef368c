"""Progress: a tqdm bar for long runs (a widget in Jupyter), one line per optimiser iteration.

A run made of parts (a line paid out by elements integrates each segment of constant ``n`` on
its own) shows one bar for the whole run: :func:`stage` opens it, and every :class:`Progress` of
the same label made inside it moves that bar instead of drawing its own (a pipe got one line
``100% 10/10`` per segment, up to 200 of them, naming no stage).
"""

from __future__ import annotations

import math
import sys
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager

from tqdm.auto import tqdm

# Whole units only: a simulation counts simulated seconds, and "183.6/210" read as a fraction.
BAR_FORMAT = (
    "{desc}: {percentage:3.0f}%|{bar}| {n_fmt}/{total_fmt} [{elapsed}<{remaining}{postfix}]"
)
# tqdm.auto chose Jupyter's widget: its bar class derives from tqdm.notebook's.
IN_NOTEBOOK = any(cls.__module__ == "tqdm.notebook" for cls in tqdm.__mro__)


class Progress:
    """Report the progress of ``total`` units of work with ``tqdm.auto``, or nothing when ``quiet``.

    Counts are whole units (of ``total``, rounded up). In Jupyter a widget; in a terminal a bar on
    stderr, cleared when it closes so that it leaves nothing among the lines printed after it,
    with the lines printed while it runs (:class:`IterationLog`) above it. Where stderr is not a
    terminal (a log file, a pipe) there is no bar: one line on stderr when it closes, so a log
    reads line by line. Simulations, Nelder-Mead, the closed loop and sweeps show their progress
    through it.

    Parameters
    ----------
    label : str
    total : float
        Units of work (e.g. simulated seconds).
    quiet : bool
        No bar at all: nothing is printed.
    """

    def __init__(self, label: str, total: float, quiet: bool = False):
        self.total, self.label = float(total), label
        self.bar = None
        self.count, self.note, self.start = 0, "", time.perf_counter()
        # A part of a stage (see stage()) moves the stage's bar.
        self.stage = next((s for s in reversed(_stages()) if s.parts == label), None)
        self.log = not quiet and self.stage is None and not (IN_NOTEBOOK or _terminal(sys.stderr))
        if not quiet and self.stage is None and not self.log:
            self.bar = tqdm(
                total=_whole(self.total),
                desc=label,
                file=sys.stderr,
                bar_format=BAR_FORMAT,
                dynamic_ncols=True,
                leave=IN_NOTEBOOK,
            )

    def update(self, done: float, note: str = "") -> None:
        """Move the bar to ``done`` units (whole units done), with a ``note`` after it."""
        done = min(max(float(done), 0.0), self.total)
        if self.stage is not None:
            self.stage.progress.update(self.stage.done + done, note)
            return
        whole = _whole(self.total)
        self.count = whole if done >= self.total else min(int(done), whole)
        self.note = note or self.note
        if self.bar is None:
            return
        if note:
            self.bar.set_postfix_str(note, refresh=False)
        if self.count != self.bar.n:
            self.bar.update(self.count - self.bar.n)

    def close(self) -> None:
        """Finish: the bar cleared in a terminal, kept in Jupyter; a log gets its one line."""
        if self.stage is not None:
            self.stage.done += self.total
            self.stage = None
        elif self.bar is not None:
            self.bar.close()
        elif self.log:
            whole = _whole(self.total)
            elapsed = tqdm.format_interval(time.perf_counter() - self.start)
            note = f", {self.note}" if self.note else ""
            write_line(f"{self.label}: {100 * self.count / whole:3.0f}% {self.count}/{whole} "
                       f"[{elapsed}{note}]")  # fmt: skip
            self.log = False


class _Stage:
    """A bar for a run of parts: ``parts`` is their label, ``done`` the units of closed parts."""

    def __init__(self, progress: Progress, parts: str):
        self.progress, self.parts, self.done = progress, parts, 0.0


_LOCAL = threading.local()  # each thread's open stages (a sweep's workers run in threads)


def _stages() -> list[_Stage]:
    if not hasattr(_LOCAL, "stages"):
        _LOCAL.stages = []
    return _LOCAL.stages


@contextmanager
def stage(label: str, total: float, parts: str = "simulate", quiet: bool = False) -> Iterator[None]:
    """One bar, ``label``, for a run of ``total`` units made of parts (see the module docstring).

    Parameters
    ----------
    label : str
        What the run is, e.g. ``"simulate deploy (line on the drum)"``.
    total : float
        Units of the whole run (simulated seconds for ``"simulate"`` parts).
    parts : str
        The label of the :class:`Progress` objects that are its parts, made one after another
        inside the block; each moves the bar from where the parts before it ended.
    quiet : bool
        No bar, and none of the parts' either.
    """
    progress = Progress(label, total, quiet)
    _stages().append(_Stage(progress, parts))
    try:
        yield
    finally:
        _stages().pop()
        progress.close()


def _whole(total: float) -> int:
    """The bar's total in whole units: ``total`` rounded up, at least 1."""
    return max(1, math.ceil(total - 1e-9)) if math.isfinite(total) else 1


def _terminal(stream) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):  # no isatty, or a closed stream
        return False


def write_line(text: str) -> None:
    """Write a line to stderr above any running bar (which is redrawn below it)."""
    tqdm.write(text, file=sys.stderr)
    sys.stderr.flush()


def check_verbosity(quiet: bool, verbose: bool) -> None:
    """Reject ``quiet`` and ``verbose`` together, before any work."""
    if quiet and verbose:
        raise ValueError("quiet = True and verbose = True: choose one (quiet prints nothing)")


class IterationLog:
    """One line per optimiser iteration on stderr, or nothing when ``quiet``.

    Parameters
    ----------
    label : str
    quiet : bool
    """

    def __init__(self, label: str, quiet: bool = False):
        self.label, self.quiet = label, quiet
        self.runs = 0
        self.start = time.perf_counter()

    def restart(self) -> None:
        """Start the clock of the next solve; solves after the first are numbered."""
        self.runs += 1
        self.start = time.perf_counter()

    def line(self, iteration: int, omega: float, violation: float) -> None:
        """Report an iteration: ``omega`` (m) and the constraint violation."""
        if self.quiet:
            return
        run = f" solve {self.runs}" if self.runs > 1 else ""
        elapsed = time.perf_counter() - self.start
        write_line(
            f"{self.label}{run} iter {iteration:4d}  Omega = {omega:.3e} m  "
            f"violation = {violation:.1e}  {elapsed:7.1f} s"
        )
