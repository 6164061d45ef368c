"""Checks for the loaders of saved results: JSON read safely, each field of its declared type.

A results file comes from disk and may be truncated, edited or not ours at all. The loaders of
result format 1 (``OcpResult.load``, ``Trajectory.load`` of json + npz) read it through
:func:`parse_json` and :func:`record_fields`; those of format 2 (netCDF,
:func:`cable_ocp.scene.labelled.from_dataset`) check each field with the same
:func:`check_field`. Whatever is wrong is one ``ValueError`` naming the file and the field, never
a ``RecursionError``, a ``TypeError`` later on, or a result that is quietly wrong.
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


def _named(kind: Any) -> str:
    return _EXPECTED.get(kind, "a value")


def check_field(name: str, value: Any, kind: Any, nan: bool = False) -> Any:
    """``value`` of the field ``name`` as type ``kind``, converted; ValueError if it is not one.

    The one check of a saved field, for both result formats: JSON's values (format 1) and a
    netCDF file's (format 2, with ``nan=True``).

    Parameters
    ----------
    name : str
        The field, as the error names it (``history[1]`` for an item).
    value : any
        The value read (NumPy scalars are taken as the Python ones).
    kind : type
        ``str``, ``bool``, ``int`` (a count, >= 0), ``float`` (finite, or null for NaN),
        ``np.ndarray`` (of numbers), ``list[...]``, ``tuple[...]`` (of a fixed length, or with
        ``...``), ``dict[str, ...]`` or ``dict``; any other type is left to its class.
    nan : bool
        Whether a float may be NaN itself (netCDF's null), not only null (JSON's).

    Raises
    ------
    ValueError
        Naming the field, the value and the type expected.
    """
    if isinstance(value, np.generic):
        value = value.item()
    origin, args = typing.get_origin(kind), typing.get_args(kind)
    if origin is list:
        (item,) = args or (Any,)
        if isinstance(value, list):
            return [check_field(f"{name}[{k}]", v, item, nan) for k, v in enumerate(value)]
        raise ValueError(f"{name} = {value!r:.40}: expected a list of {_named(item)}s")
    if origin is tuple:
        free = args[1:] == (Ellipsis,)  # tuple[float, ...]: any length
        if not isinstance(value, list | tuple) or not (free or len(value) == len(args)):
            size = "any number of" if free else len(args)
            raise ValueError(f"{name} = {value!r:.40}: expected {size} values, each "
                             f"{_named(args[0] if args else Any)}")  # fmt: skip
        items = args[:1] * len(value) if free else args
        return tuple(check_field(f"{name}[{k}]", v, t, nan) for k, (v, t) in
                     enumerate(zip(value, items, strict=True)))  # fmt: skip
    if kind is dict or origin is dict:
        if not isinstance(value, dict) or not all(isinstance(k, str) for k in value):
            raise ValueError(f"{name} = {value!r:.40}: expected a mapping of names")
        if not args:
            return value
        return {k: check_field(f"{name}[{k!r}]", v, args[1], nan) for k, v in value.items()}
    if kind is np.ndarray:
        if isinstance(value, np.ndarray) and value.dtype.kind in "biuf":
            return value
        held = (f"an array of {value.dtype} of shape {value.shape}" if isinstance(value, np.ndarray)
                else f"{value!r:.40}")  # fmt: skip
        raise ValueError(f"{name} = {held}: expected an array of numbers")
    fits = {
        str: isinstance(value, str),
        bool: isinstance(value, bool),
        int: isinstance(value, int) and not isinstance(value, bool) and value >= 0,
        float: value is None
        or _number(value)
        or (nan and isinstance(value, float) and math.isnan(value)),
    }
    if kind not in fits:
        return value  # a type a record does not declare: left to its class
    if not fits[kind]:
        expected = "a finite number or NaN" if nan and kind is float else _named(kind)
        raise ValueError(f"{name} = {value!r:.40}: expected {expected}")
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
        Field name -> type (those of :func:`check_field`), e.g. from ``typing.get_type_hints``
        of the record's class.
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
    return {name: check_field(name, value, types[name]) for name, value in meta.items()}


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


def check_run(time: np.ndarray, positions: dict[str, np.ndarray]) -> None:
    """Check the series of a saved run: its ``time`` (s) and its ``positions`` (m), by name.

    Raises
    ------
    ValueError
        Naming the field: a time that is not finite or not strictly increasing, or a position
        that is not finite (NaN or infinite).
    """
    time = np.asarray(time, dtype=float)
    if not np.isfinite(time).all():
        raise ValueError("time: not all finite")
    steps = np.flatnonzero(np.diff(time) <= 0)
    if steps.size:
        k = int(steps[0])
        after = f"{time[k + 1]:g} s after {time[k]:g} s"
        raise ValueError(f"time: not strictly increasing ({after} at index {k + 1})")
    for name, values in positions.items():
        if not np.isfinite(np.asarray(values, dtype=float)).all():
            raise ValueError(f"{name}: not all finite (NaN or infinite positions)")
