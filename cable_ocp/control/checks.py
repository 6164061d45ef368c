"""The settings' fields checked by the one field rule of the scenes, one message per failure.

Every settings class of the optimisers and the closed loop (``ModelSettings``, ``GridSettings``,
``TranscriptionSettings``, ``IpoptSettings``, ``GaussNewtonSettings``, ``NelderMeadSettings``,
``MpcSettings``) lists its numeric, choice and flag fields with a :func:`Rule` and calls
:func:`check_fields` from ``__post_init__``: a value of the wrong type (a bool for an integer,
a string for a number), NaN, infinity or one out of range is a ``ValueError`` naming the field,
its value and what it must be, before anything is built. The rule and its check are the scene
fields' own (:class:`cable_ocp.scene.rules.FieldRule`); only the wording is the settings'.
"""

from __future__ import annotations

import contextlib
import os
import sys

from cable_ocp.scene.rules import FieldRule

# A settings rule's kind -> the field rule's.
KINDS = {"integer": "int", "number": "float", "choice": "choice", "flag": "bool", "table": "table"}


def Rule(  # noqa: N802 - the settings classes' name for their field rules
    kind: str,
    low: float | None = None,
    high: float | None = None,
    above: float | None = None,
    unit: str = "",
    optional: bool = False,
    choices: tuple[str, ...] = (),
) -> FieldRule:
    """What one settings field may hold, as a :class:`~cable_ocp.scene.rules.FieldRule`.

    Parameters
    ----------
    kind : str
        ``"integer"``, ``"number"`` (a finite real), ``"choice"``, ``"flag"`` (a bool) or
        ``"table"`` (a dict).
    low, high : float or None
        Smallest and largest value allowed (inclusive), or None.
    above : float or None
        A bound the value must be strictly above, or None.
    unit : str
        Printed after the value.
    optional : bool
        None is allowed (a setting derived from the scene).
    choices : tuple of str
        For ``"choice"``.
    """
    if kind not in KINDS:
        raise ValueError(f"Rule kind = {kind!r}: must be one of {', '.join(KINDS)}")
    return FieldRule(KINDS[kind], unit=unit, gt=above, ge=low, le=high, optional=optional,
                     choices=tuple(choices))  # fmt: skip


def problem(rule: FieldRule, value) -> str | None:
    """What is wrong with ``value`` under ``rule``, in the settings' words (None when allowed)."""
    fault = rule.fault(value)
    if fault is None:
        return None
    if fault.what == "choice":
        return f"must be one of {', '.join(rule.choices)}"
    return f"must be {fault.expected}"


def check_fields(settings, rules: dict[str, FieldRule]) -> None:
    """Raise a ValueError naming the first field of ``settings`` that breaks its rule."""
    for name, rule in rules.items():
        value = getattr(settings, name)
        text = problem(rule, value)
        if text is not None:
            unit = f" {rule.unit}" if rule.unit and value is not None else ""
            raise ValueError(f"{type(settings).__name__}.{name} = {value!r}{unit}: {text}")


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
