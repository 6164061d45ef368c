"""A small text progress bar on stderr for long simulations and optimisations."""

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
