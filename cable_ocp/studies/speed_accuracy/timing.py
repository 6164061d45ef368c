"""CPU and wall time of a call."""

from __future__ import annotations

import time
from collections.abc import Callable


def timed(call: Callable[[], object]) -> tuple[object, float, float]:
    """Call ``call()``; return its value, the CPU time of this process and the wall time (s)."""
    cpu, wall = time.process_time(), time.perf_counter()
    value = call()
    return value, time.process_time() - cpu, time.perf_counter() - wall
