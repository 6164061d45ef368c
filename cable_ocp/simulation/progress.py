"""Progress: a tqdm bar for long runs (a widget in Jupyter), one line per optimiser iteration."""

from __future__ import annotations

import sys
import time

from tqdm.auto import tqdm

BAR_FORMAT = (
    "{desc}: {percentage:3.0f}%|{bar}| {n:.4g}/{total:.4g} [{elapsed}<{remaining}{postfix}]"
)


class Progress:
    """Report the progress of ``total`` units of work with ``tqdm.auto``, or nothing when ``quiet``.

    In a terminal a bar on stderr; in Jupyter a widget. Simulations, Nelder-Mead, the closed loop
    and sweeps show their progress through it.

    Parameters
    ----------
    label : str
    total : float
        Units of work (e.g. simulated seconds).
    quiet : bool
        No bar at all: nothing is printed.
    """

    def __init__(self, label: str, total: float, quiet: bool = False):
        self.total = float(total)
        self.bar = None
        if not quiet:
            self.bar = tqdm(total=self.total, desc=label, file=sys.stderr, bar_format=BAR_FORMAT,
                            dynamic_ncols=True, leave=True)  # fmt: skip

    def update(self, done: float, note: str = "") -> None:
        """Move the bar to ``done`` units, with a ``note`` after it."""
        if self.bar is None:
            return
        if note:
            self.bar.set_postfix_str(note, refresh=False)
        self.bar.update(min(max(float(done), 0.0), self.total) - self.bar.n)

    def close(self) -> None:
        """Finish the bar (drawn once more at its last value)."""
        if self.bar is not None:
            self.bar.close()


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
