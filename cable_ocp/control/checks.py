"""One way to check the fields of a settings class: declared rules, one message per failure.

Every settings class of the optimisers and the closed loop (``ModelSettings``, ``GridSettings``,
``TranscriptionSettings``, ``IpoptSettings``, ``GaussNewtonSettings``, ``NelderMeadSettings``,
``MpcSettings``) lists its numeric, choice and flag fields with a :class:`Rule` and calls
:func:`check_fields` from ``__post_init__``: a value of the wrong type (a bool for an integer,
a string for a number), NaN, infinity or one out of range is a ``ValueError`` naming the field,
its value and what it must be, before anything is built.
"""

from __future__ import annotations

import contextlib
import math
import numbers
import os
import sys
from dataclasses import dataclass


@dataclass(frozen=True)
class Rule:
    """What one field may hold.

    Attributes
    ----------
    kind : str
        ``"integer"``, ``"number"`` (a finite real), ``"choice"``, ``"flag"`` (a bool) or
        ``"table"`` (a dict).
    low : float or None
        Smallest value allowed (inclusive), or None.
    high : float or None
        Largest value allowed (inclusive), or None.
    above : float or None
        A bound the value must be strictly above, or None.
    unit : str
        Printed after the value.
    optional : bool
        None is allowed (a setting derived from the scene).
    choices : tuple of str
        For ``"choice"``.
    """

    kind: str
    low: float | None = None
    high: float | None = None
    above: float | None = None
    unit: str = ""
    optional: bool = False
    choices: tuple[str, ...] = ()

    def problem(self, value) -> str | None:
        """What is wrong with ``value`` (None when it is allowed)."""
        if value is None:
            return None if self.optional else "must be set"
        if self.kind == "choice":
            return None if value in self.choices else f"must be one of {', '.join(self.choices)}"
        if self.kind == "flag":
            return None if isinstance(value, bool) else "must be true or false"
        if self.kind == "table":
            return None if isinstance(value, dict) else "must be a table (a dict)"
        if isinstance(value, bool) or not isinstance(value, numbers.Real):
            return f"must be {'an integer' if self.kind == 'integer' else 'a number'}"
        if self.kind == "integer" and not isinstance(value, numbers.Integral):
            return "must be an integer"
        if not math.isfinite(value):
            return "must be finite"
        if self.high is not None and value > self.high:
            return f"must be <= {self.high:g}"
        if self.low is not None and value < self.low:
            return f"must be >= {self.low:g}"
        if self.above is not None and not value > self.above:
            return f"must be > {self.above:g}"
        return None


def check_fields(settings, rules: dict[str, Rule]) -> None:
    """Raise a ValueError naming the first field of ``settings`` that breaks its rule."""
    for name, rule in rules.items():
        value = getattr(settings, name)
        problem = rule.problem(value)
        if problem is not None:
            unit = f" {rule.unit}" if rule.unit and value is not None else ""
            raise ValueError(f"{type(settings).__name__}.{name} = {value!r}{unit}: {problem}")


def check_ipopt_options(options: dict) -> None:
    """Raise a ValueError naming an IPOPT option that IPOPT does not take (before any solve).

    The options are handed to IPOPT on a one-variable problem, its output silenced.
    """
    if not options:
        return
    import casadi as ca

    x = ca.SX.sym("x")
    quiet = {"print_level": 0, "sb": "yes"}
    try:
        with _silenced():
            ca.nlpsol(
                "ipopt_options_check",
                "ipopt",
                {"x": x, "f": x**2},
                {"ipopt": {**options, **quiet}, "print_time": False},
            )
    except RuntimeError as error:
        last = str(error).strip().splitlines()[-1].split(": ", 1)[-1]
        raise ValueError(f"ipopt_options = {options!r}: IPOPT refuses them ({last})") from None


@contextlib.contextmanager
def _silenced():
    """Send the process's C-level standard output to /dev/null for the block."""
    sys.stdout.flush()
    saved = os.dup(1)
    try:
        with open(os.devnull, "w") as null:
            os.dup2(null.fileno(), 1)
            yield
    finally:
        os.dup2(saved, 1)
        os.close(saved)
