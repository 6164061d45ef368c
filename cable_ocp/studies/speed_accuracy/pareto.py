"""The Pareto front of cost against error."""

from __future__ import annotations

import math
from collections.abc import Sequence


def pareto_front(costs: Sequence[float], errors: Sequence[float]) -> list[int]:
    """Indices of the non-dominated points, cheapest first.

    A point is dominated when another is no dearer and no less accurate, and better in one of the
    two.
    """
    order = sorted(range(len(costs)), key=lambda k: (costs[k], errors[k]))
    front, best = [], math.inf
    for k in order:
        if errors[k] < best:
            front.append(k)
            best = errors[k]
    return front
