"""Units and long names of a result's fields, for the netCDF files and ``summary()``.

A result class declares the unit of each field that it stores as a variable, once, beside its
fields: a ``UNITS`` mapping (a ``ClassVar``) from field name to the unit in the udunits spelling
of CF (``"m s-1"``, ``"1"`` for a count or a ratio). :func:`field_units` reads it, and
:func:`unit_of` refuses a field that has none: a result with an undeclared unit is not written.

The numpydoc ``Attributes`` section states the same units for the reader (``omega : float,
m``); :func:`docstring_units` reads them so that a test keeps the two equal, and a unit there that
is not a unit (``metres a second``) is an error.

Long names (CF ``long_name``) are the first sentence of each field's description in that
section (:func:`long_names`); a field without one is named by its name.
"""

from __future__ import annotations

import inspect
import re
from functools import cache

import xarray as xr

DIMENSIONLESS = "1"
# Symbols a result's docstring may state, each with an optional power: ``m/s^2``, ``N m``,
# ``1/s``, ``%``.
SYMBOLS = ("m", "s", "ms", "us", "kg", "N", "rad", "Pa", "J", "W", "Hz", "%")
TERM = rf"(?:{'|'.join(SYMBOLS)})(?:\^-?\d+)?"
UNIT = re.compile(rf"^(?:{TERM}|1(?=/|$))(?:[ ·/]{TERM})*$")
# Last parts of a numpydoc type that are not units: an optional field (no unit), and a unit
# that depends on the instance (the caller gives it, ``to_dataset(units=...)``).
NO_UNIT, PER_INSTANCE = "optional", "rad or m"


def _top_level_split(text: str) -> list[str]:
    """``"array (k, 3), m"`` -> ``["array (k, 3)", "m"]``: commas outside brackets."""
    parts, depth, current = [], 0, ""
    for char in text:
        depth += char in "([{"
        depth -= char in ")]}"
        if char == "," and depth == 0:
            parts.append(current.strip())
            current = ""
        else:
            current += char
    return [*parts, current.strip()]


def cf_units(unit: str) -> str:
    """A docstring unit in the udunits spelling of CF: ``m/s^2`` -> ``m s-2``, ``m^2`` -> ``m2``.

    ``%`` is ``percent``, the name udunits gives it.
    """
    numerator, *denominators = unit.replace("·", " ").replace("%", "percent").split("/")
    terms = [re.sub(r"\^(-?\d+)", r"\1", t) for t in numerator.split() if t != DIMENSIONLESS]
    for term in denominators:
        name, _, power = term.strip().partition("^")
        terms.append(f"{name}-{power or 1}")
    return " ".join(terms) or DIMENSIONLESS


@cache
def _attributes(cls: type) -> dict[str, tuple[str, str]]:
    """``{field: (type, description)}`` from the numpydoc ``Attributes`` section of ``cls``."""
    lines = inspect.cleandoc(cls.__doc__ or "").splitlines()
    entries: dict[str, tuple[str, str]] = {}
    try:
        start = next(i for i, line in enumerate(lines[:-1]) if line.strip() == "Attributes"
                     and set(lines[i + 1].strip()) == {"-"}) + 2  # fmt: skip
    except StopIteration:
        return entries
    k = start
    while k < len(lines):
        line = lines[k]
        if k + 1 < len(lines) and lines[k + 1].strip() and set(lines[k + 1].strip()) == {"-"}:
            break  # the next section
        k += 1
        if not line or line[0].isspace():
            continue
        names, _, kind = line.partition(" : ")
        text = []
        while k < len(lines) and lines[k].strip() and lines[k][0].isspace():
            text.append(lines[k].strip())
            k += 1
        for name in (n.strip() for n in names.split(",")):
            entries[name] = (kind, " ".join(text))
    return entries


@cache
def long_names(cls: type) -> dict[str, str]:
    """``{field: long_name}``: the first sentence of each field's description in ``cls``."""
    names = {}
    for name, (_, text) in _attributes(cls).items():
        sentence = _plain(re.split(r"\.(?:\s+(?=[A-Z])|$)", text)[0])
        names[name] = sentence or name.replace("_", " ")
    return names


@cache
def field_units(cls: type) -> dict[str, str]:
    """``{field: units}`` (CF spelling) that ``cls`` declares in its ``UNITS``.

    Raises
    ------
    ValueError
        ``cls`` declares no ``UNITS``, naming it.
    """
    declared = getattr(cls, "UNITS", None)
    if declared is None:
        raise ValueError(
            f"{cls.__name__} declares no UNITS: a result class names the CF unit of every field "
            "it stores as a variable in a UNITS mapping beside its fields (result_files.units)"
        )
    return dict(declared)


@cache
def docstring_units(cls: type) -> dict[str, str]:
    """``{field: units}`` (CF spelling) stated in the ``Attributes`` section of ``cls``.

    A field documented without a unit (``steps : int``) is dimensionless, ``"1"``; one whose
    unit depends on the instance (``rad or m``) is left out.

    Raises
    ------
    ValueError
        Naming the class and the field: a unit that is not a unit (``metres a second``).
    """
    units = {}
    for name, (kind, _) in _attributes(cls).items():
        parts = _top_level_split(kind)
        unit = parts[-1] if len(parts) > 1 else NO_UNIT
        if unit == PER_INSTANCE:
            continue
        if unit != NO_UNIT and not UNIT.match(unit):
            raise ValueError(f"{cls.__name__}.{name} : {kind}: {unit!r} is not a unit")
        units[name] = DIMENSIONLESS if unit == NO_UNIT else cf_units(unit)
    return units


def unit_of(cls: type, name: str) -> str:
    """The unit that ``cls`` declares for its field ``name``.

    Raises
    ------
    ValueError
        The field has no declared unit (name it in ``cls.UNITS``; ``"1"`` for a count).
    """
    try:
        return field_units(cls)[name]
    except KeyError:
        raise ValueError(
            f"{cls.__name__}.{name}: no declared unit (add it to {cls.__name__}.UNITS, "
            f'"1" for a count or a ratio)'
        ) from None


def units_of(cls: type, names) -> dict[str, str]:
    """``{name: units}`` of the fields ``names`` of ``cls`` that have a unit (not ``"1"``)."""
    units = field_units(cls)
    return {name: units[name] for name in names
            if name in units and units[name] != DIMENSIONLESS}  # fmt: skip


def _plain(text: str) -> str:
    """Docstring text without reST markup: ``:data:`x```, double backquotes."""
    text = re.sub(r":\w+:`~?\.?([^`]*)`", r"\1", text)
    return text.replace("``", "").strip()


def describe(
    variable: xr.DataArray | xr.Variable, units: str, long_name: str
) -> xr.DataArray | xr.Variable:
    """Set the CF attributes ``units`` and ``long_name`` of a variable; returns it."""
    variable.attrs.update(units=units, long_name=long_name)
    return variable
