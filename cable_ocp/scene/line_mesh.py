"""The mesh of a line paid out and hauled in: how many elements, and how long the top one is.

Every element below the top is ``Delta`` long (element 0, at the end, ``Delta / 2``, as the
paper divides a line, eq. 1); the top element takes the rest of the line out,
``l_n = L_out - (n - 1/2) Delta``, and is kept within ``[l_min, l_min + 3/2 Delta]``
(CONVENTIONS.md §3, the line on the drum). When the drum pays it out past the top of that range
an element of ``Delta`` is split off below it (``n + 1``, the top left ``>= l_min + Delta / 2``);
when it hauls it in below ``l_min`` the top element is merged with the one below it (``n - 1``,
the top ``<= l_min + Delta``). Half an element of hysteresis on either side keeps a winch that
turns to and fro about a change from splitting and merging at every sample.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

# Fewest elements below the top: the structured loops need n >= 2 (three elements in all).
FEWEST_ELEMENTS = 2
# The top element's range, in segment lengths above its shortest.
TOP_RANGE = 1.5


@dataclass(frozen=True)
class LineMesh:
    """Element lengths of a paid-out line.

    Attributes
    ----------
    element_length : float, m
        ``Delta``, every element between the end's (``Delta / 2``) and the top one.
    top_length_min : float, m
        ``l_min``, the shortest top element; the longest is ``l_min + 3/2 Delta``.
    """

    element_length: float
    top_length_min: float

    @property
    def top_length_max(self) -> float:
        """``l_min + 3/2 Delta`` (m): beyond it an element is split off."""
        return self.top_length_min + TOP_RANGE * self.element_length

    @property
    def shortest_line(self) -> float:
        """The least line out (m): ``n = 2`` with the shortest top element."""
        return (FEWEST_ELEMENTS - 0.5) * self.element_length + self.top_length_min

    def below_top(self, elements: int) -> float:
        """Line in the elements below the top (m): ``(n - 1/2) Delta``."""
        return (elements - 0.5) * self.element_length

    def starting_elements(self, line: float) -> int:
        """``n`` at the start: the top element in ``[l_min, l_min + Delta)`` of ``line`` (m)."""
        n = int(np.floor((line - self.top_length_min) / self.element_length + 0.5))
        return max(n, FEWEST_ELEMENTS)

    def schedule(self, lines: np.ndarray, start: int) -> np.ndarray:
        """``n`` at each sample of the line out ``lines`` (m), from ``start`` at the first.

        A split when the top element would be longer than :attr:`top_length_max`, a merge when
        it would be shorter than ``l_min`` (never below :data:`FEWEST_ELEMENTS`).
        """
        counts = np.empty(len(lines), dtype=int)
        n = start
        for k, line in enumerate(lines):
            while line - self.below_top(n) > self.top_length_max:
                n += 1
            while n > FEWEST_ELEMENTS and line - self.below_top(n) < self.top_length_min:
                n -= 1
            counts[k] = n
        return counts
