"""The lowering's numeric arguments checked where they enter, each error naming the argument."""

from __future__ import annotations

import math
import numbers


def real_number(name: str, value, unit: str) -> float:
    """``value`` as a finite float, or an error naming the argument ``name`` (in ``unit``).

    Raises
    ------
    TypeError
        Not a real number (a string, a bool, None, a list).
    ValueError
        NaN or infinite.
    """
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(
            f"{name} = {value!r:.40}: must be a number ({unit}), not {type(value).__name__}"
        )
    if not math.isfinite(value):
        raise ValueError(f"{name} = {value!r} {unit} is out of range: must be finite")
    return float(value)
