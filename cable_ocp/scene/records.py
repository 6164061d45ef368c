"""Checks for the loaders of saved results: JSON read safely, each field of its declared type.

A results file comes from disk and may be truncated, edited or not ours at all. The loaders
(``OcpResult.load``, ``Trajectory.load``) read it through :func:`parse_json` and
:func:`record_fields`, so that whatever is wrong is one ``ValueError`` naming the file and the
field, never a ``RecursionError``, a ``TypeError`` later on, or a result that is quietly wrong.
"""

from __future__ import annotations

import json
import math
import re
import typing
from pathlib import Path
from typing import Any

import numpy as np

# The types a field of a saved record may have, and how an error names them.
_EXPECTED = {str: "a string", bool: "true or false", int: "an integer >= 0",
             float: "a finite number or null"}  # fmt: skip
# How a control is named in a result: its kind and its number of parameters, "hermite(84)".
CONTROL = re.compile(r"(?P<kind>[a-z-]+)\((?P<size>[0-9]+)\)")


def parse_json(text: str) -> Any:
    """``json.loads``, with a file nested too deeply for Python a ``ValueError`` too."""
    try:
        return json.loads(text)
    except RecursionError:
        raise ValueError("JSON nested too deeply") from None


def read_json(path: str | Path) -> Any:
    """The JSON value in the file ``path``.

    Raises
    ------
    ValueError
        Naming the file, if it cannot be read, is not UTF-8 or not JSON.
    """
    try:
        return parse_json(Path(path).read_text(encoding="utf-8"))
    except (OSError, ValueError) as error:  # UnicodeDecodeError, JSONDecodeError included
        raise ValueError(f"{path}: {type(error).__name__}: {error}") from None


def _number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)


def _field(name: str, value: Any, kind: Any) -> Any:
    """``value`` of the field ``name`` as type ``kind``; ValueError if it is not one."""
    if typing.get_origin(kind) is list:
        (item,) = typing.get_args(kind) or (Any,)
        if isinstance(value, list):
            return [_field(f"{name}[{k}]", v, item) for k, v in enumerate(value)]
        raise ValueError(f"{name} = {value!r:.40}: expected a list of {_EXPECTED[item]}s")
    fits = {
        str: isinstance(value, str),
        bool: isinstance(value, bool),
        int: isinstance(value, int) and not isinstance(value, bool) and value >= 0,
        float: value is None or _number(value),
    }
    if kind not in fits:
        return value  # a type a record does not declare: left to its class
    if not fits[kind]:
        raise ValueError(f"{name} = {value!r:.40}: expected {_EXPECTED[kind]}")
    if kind is float:
        return float("nan") if value is None else float(value)
    return value


def record_fields(meta: Any, types: dict[str, Any], optional: set[str] = frozenset()) -> dict:
    """The fields of a saved record, each checked against its type and converted.

    Parameters
    ----------
    meta : any
        The JSON value read from the file (a dict if it is a record).
    types : dict
        Field name -> type (``str``, ``bool``, ``int`` (>= 0), ``float`` (null is NaN) or
        ``list[...]`` of those), e.g. from ``typing.get_type_hints`` of the record's class.
    optional : set of str
        Fields that older files lack (the class's defaults fill them).

    Raises
    ------
    ValueError
        Naming the missing, unknown or ill-typed field (the caller adds the file).
    """
    if not isinstance(meta, dict):
        raise ValueError(f"expected a JSON object of fields, got {type(meta).__name__}")
    missing = sorted(set(types) - set(optional) - set(meta))
    unknown = sorted(set(meta) - set(types))
    if missing or unknown:
        detail = "; ".join(
            part
            for part in (
                f"missing field(s) {', '.join(missing)}" if missing else "",
                f"unknown field(s) {', '.join(map(str, unknown))[:80]}" if unknown else "",
            )
            if part
        )
        raise ValueError(detail)
    return {name: _field(name, value, types[name]) for name, value in meta.items()}


def control_size(control: str) -> int:
    """The number of parameters of a control named ``kind(size)``, e.g. ``"hermite(84)"``.

    Raises
    ------
    ValueError
        Naming the field, if ``control`` is not of that form.
    """
    match = CONTROL.fullmatch(control)
    if match is None:
        raise ValueError(
            f"control = {control!r:.40}: expected a name and a size, e.g. 'spline(14)'"
        )
    return int(match["size"])


def control_parameters(parameters: np.ndarray, control: str) -> np.ndarray:
    """Check that winch ``parameters`` fit their ``control`` (``"hermite(84)"``: 84 numbers).

    Raises
    ------
    ValueError
        Naming the field: a control not of the form ``kind(size)``, or parameters of another
        shape or not finite.
    """
    size = control_size(control)
    if parameters.shape != (size,):
        raise ValueError(
            f"parameters of shape {parameters.shape}: control = {control!r} has {size} parameters"
        )
    if not np.isfinite(parameters).all():
        raise ValueError("parameters: not all finite")
    return parameters
