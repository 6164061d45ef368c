"""Progress on stderr: a text bar for long runs, one line per iteration for optimisers."""

from __future__ import annotations

import sys
import time


class Progress:
    """Report the progress of ``total`` units of work, or nothing when ``quiet``.

    Parameters
    ----------
    label : str
    total : float
        Units of work (e.g. simulated seconds).
    quiet : bool
    """

    WIDTH = 30

    def __init__(self, label: str, total: float, quiet: bool = False):
        self.label, self.total, self.quiet = label, total, quiet
        self.start = time.perf_counter()

    def update(self, done: float, note: str = "") -> None:
        """Redraw the bar at ``done`` units."""
        if self.quiet:
            return
        fraction = min(max(done / self.total, 0.0), 1.0) if self.total else 1.0
        filled = int(round(fraction * self.WIDTH))
        elapsed = time.perf_counter() - self.start
        bar = "#" * filled + "-" * (self.WIDTH - filled)
        sys.stderr.write(f"\r{self.label} [{bar}] {100 * fraction:5.1f}% {elapsed:7.1f} s {note}")
        sys.stderr.flush()

    def close(self) -> None:
        """End the line of the bar."""
        if not self.quiet:
            sys.stderr.write("\n")
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
        sys.stderr.write(
            f"{self.label}{run} iter {iteration:4d}  Omega = {omega:.3e} m  "
            f"violation = {violation:.1e}  {elapsed:7.1f} s\n"
        )
        sys.stderr.flush()
