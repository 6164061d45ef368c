"""Numbers in messages, with enough digits to tell a value from the limit it broke."""

from __future__ import annotations


def apart(value: float, limit: float) -> tuple[str, str]:
    """``value`` and ``limit`` formatted with the fewest significant digits (3 or more) that differ.

    A residual of 0.000100049 m over a tolerance of 0.0001 m reads ``0.00010005`` and ``0.0001``,
    not ``0.0001`` twice.
    """
    for digits in range(3, 18):
        shown = f"{value:.{digits}g}"
        if float(shown) != limit or value == limit:
            return shown, f"{limit:g}"
    return repr(value), repr(limit)
