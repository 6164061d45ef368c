"""One field's rule, and the one check of a value against it: for scene fields and settings alike.

A :class:`FieldRule` declares what a field may hold: its kind, its range, its unit, whether it may
be None, its choices, and the physical reason for the range. :meth:`FieldRule.fault` is the one
check of a value against it (a bool is no number, a float no integer, NaN and infinity are out
of range), and returns what is wrong as a :class:`Fault`. The scene's fields
(:mod:`cable_ocp.scene.schema`, ``_param``) and the solvers' settings
(:mod:`cable_ocp.control.checks`, ``Rule``) declare their fields with it and word the fault in
their own way: a scene by the field's dotted path (:class:`SceneError`), a settings class by its
attribute.
"""

from __future__ import annotations

import math
import numbers
import operator
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

EXPECTED = {
    "int": "an integer",
    "float": "a number",
    "vec3": "a number",
    "bool": "true or false",
    "str": "a string",
    "choice": "a string",
    "table": "a table (a dict)",
}


class SceneError(ValueError):
    """Invalid scene data; ``path`` is the dotted field path the message starts with."""

    def __init__(self, path: str, detail: str) -> None:
        self.path, self.detail = path, detail
        super().__init__(path + detail)

    def relocated(self, old: str, new: str) -> SceneError:
        """Return the same error with the path prefix ``old`` replaced by ``new``."""
        if old == new or not self.path.startswith(old):
            return self
        return SceneError(new + self.path[len(old) :], self.detail)


@dataclass(frozen=True)
class Fault:
    """What is wrong with a value, as :meth:`FieldRule.fault` finds it.

    Attributes
    ----------
    what : str
        ``"missing"`` (None where a value is needed), ``"type"`` (a value of another kind),
        ``"finite"`` (NaN, infinity, or an integer too large for a float), ``"range"`` (a
        number outside the bounds) or ``"choice"`` (a string not among the choices).
    expected : str
        What the value must be, in words: ``an integer``, ``<= 1`` (the first bound broken),
        ``one of`` the choices.
    """

    what: str
    expected: str


@dataclass(frozen=True)
class FieldRule:
    """What one field may hold.

    Attributes
    ----------
    kind : str
        ``float``, ``int``, ``bool``, ``str``, ``choice``, ``table`` (a dict), or a scene's
        ``path``, ``vec3``, ``section``, ``tuple``.
    doc : str
        The field's meaning, one line.
    unit : str
        The unit of a number (``m``, ``rad/s``; empty: none).
    gt, ge, le : float or None
        Bounds of a number: strictly above ``gt``, at least ``ge``, at most ``le`` (None: no
        bound).
    optional : bool
        None is allowed.
    choices : tuple of str
        For ``choice``.
    item : type or None
        The dataclass of a ``section``, or of the items of a ``tuple``.
    why : str
        The physical reason for the range, said when a value is out of it.
    """

    kind: str
    doc: str = ""
    unit: str = ""
    gt: float | None = None
    ge: float | None = None
    le: float | None = None
    optional: bool = False
    choices: tuple[str, ...] = ()
    item: type | None = None
    why: str = ""

    def rule(self) -> str:
        """Describe the allowed range, e.g. ``> 0 (m)``."""
        bounds = ((">", self.gt), (">=", self.ge), ("<=", self.le))
        text = " and ".join(f"{op} {bound:g}" for op, bound in bounds if bound is not None)
        return text + (f" ({self.unit})" if self.unit else "")

    def accepts(self, x: float) -> bool:
        """Whether the number ``x`` lies in the allowed range."""
        return self.broken_bound(x) is None

    def broken_bound(self, x: float) -> str | None:
        """The first bound ``x`` breaks (the upper one first), e.g. ``<= 1``; None if none."""
        for op, bound, holds in (
            ("<=", self.le, operator.le),
            (">=", self.ge, operator.ge),
            (">", self.gt, operator.gt),
        ):
            if bound is not None and not holds(x, bound):
                return f"{op} {bound:g}"
        return None

    def fault(self, value: Any) -> Fault | None:
        """What is wrong with ``value`` for this rule (None when it is allowed).

        Checks ``float``, ``int`` (and each number of a ``vec3``, as a float), ``bool``,
        ``str``, ``choice`` and ``table``; a scene's ``path``, ``section`` and ``tuple`` are
        the schema's to check.
        """
        if value is None:
            return None if self.optional else Fault("missing", "set")
        kind = "float" if self.kind == "vec3" else self.kind
        if kind in ("float", "int"):
            return _number_fault(value, kind == "int", self)
        if kind == "bool":
            return None if isinstance(value, bool) else Fault("type", EXPECTED[kind])
        if kind == "table":
            return None if isinstance(value, dict) else Fault("type", EXPECTED[kind])
        if kind in ("str", "choice") and not isinstance(value, str):
            return Fault("type", EXPECTED[kind])
        if kind == "choice" and value not in self.choices:
            return Fault("choice", "one of")
        return None


def _number_fault(value: Any, integer: bool, rule: FieldRule) -> Fault | None:
    """A number's fault: booleans are not numbers, floats are not integers, NaN is out of range."""
    want = numbers.Integral if integer else numbers.Real
    if isinstance(value, bool) or not isinstance(value, want):
        return Fault("type", EXPECTED["int" if integer else "float"])
    try:
        finite = math.isfinite(float(value))
    except OverflowError:  # an integer too large for a float
        finite = integer
    if not finite:
        return Fault("finite", "finite")
    broken = rule.broken_bound(value)
    return None if broken is None else Fault("range", broken)


def finite_array(
    value: Any,
    name: str,
    shape: tuple[int, ...],
    of: str,
    at: Callable[[int], str] = lambda k: f"[{k}]",
    advice: str = "",
) -> np.ndarray:
    """``value`` as a float array of ``shape``, every value finite; else a ValueError naming it.

    The check of an array handed to the API (a state, a winch function's angles), as
    :meth:`FieldRule.fault` is of a field.

    Parameters
    ----------
    value : array-like
    name : str
        What it is, as the message starts (``initial_state``).
    shape : tuple of int
        The shape it must have.
    of : str
        What gives that shape (``the model's state``, ``t``).
    at : callable
        Index ``k`` (of the flattened array) -> where that value sits, for the message.
    advice : str
        Appended to every message after ``"; "`` (what a right value is).
    """
    tail = f"; {advice}" if advice else ""
    try:
        values = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{name} is {type(value).__name__}, not numbers{tail}") from None
    if values.shape != shape:
        raise ValueError(f"{name} has shape {values.shape} for {of} of shape {shape}{tail}")
    finite = np.isfinite(values).ravel()
    if not finite.all():
        k = int(np.argmin(finite))
        raise ValueError(f"{name}{at(k)} is {values.ravel()[k]}, not finite{tail}")
    return values
