"""Units and long names of a result's fields, read from its class docstring.

A result states each field's unit once, beside the field in the numpydoc ``Attributes`` section
(``omega : float, m`` and the first sentence below it); :func:`field_docs` reads them for the
netCDF files (CF ``units`` and ``long_name``) and for ``summary()``'s ``"units"`` entry.
"""

from __future__ import annotations

import inspect
import re
from functools import cache

import xarray as xr

DIMENSIONLESS = "1"
UNIT = re.compile(r"^[A-Za-z][A-Za-z0-9^/ ·-]*$")
NOT_UNITS = {"optional", "rad or m"}


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
    """A docstring unit in the udunits spelling of CF: ``m/s^2`` -> ``m s-2``, ``m^2`` -> ``m2``."""
    numerator, *denominators = unit.replace("·", " ").split("/")
    terms = [re.sub(r"\^(-?\d+)", r"\1", t) for t in numerator.split()]
    for term in denominators:
        name, _, power = term.strip().partition("^")
        terms.append(f"{name}-{power or 1}")
    return " ".join(terms) or DIMENSIONLESS


@cache
def field_docs(cls: type) -> dict[str, tuple[str, str]]:
    """``{field: (units, long_name)}`` from the numpydoc ``Attributes`` section of ``cls``.

    Units are in the CF spelling (:func:`cf_units`). A field documented without a unit gets
    ``"1"``; one not documented, ``"1"`` and its name.
    """
    lines = inspect.cleandoc(cls.__doc__ or "").splitlines()
    docs: dict[str, tuple[str, str]] = {}
    try:
        start = next(i for i, line in enumerate(lines[:-1]) if line.strip() == "Attributes"
                     and set(lines[i + 1].strip()) == {"-"}) + 2  # fmt: skip
    except StopIteration:
        return docs
    k = start
    while k < len(lines):
        line = lines[k]
        if k + 1 < len(lines) and lines[k + 1].strip() and set(lines[k + 1].strip()) == {"-"}:
            break  # the next section
        if line and not line[0].isspace():
            names, _, kind = line.partition(" : ")
            parts = _top_level_split(kind)
            unit = parts[-1] if len(parts) > 1 else ""
            unit = cf_units(unit) if UNIT.match(unit) and unit not in NOT_UNITS else DIMENSIONLESS
            text = []
            k += 1
            while k < len(lines) and (not lines[k] or lines[k][0].isspace()):
                if not lines[k].strip():
                    break
                text.append(lines[k].strip())
                k += 1
            sentence = _plain(re.split(r"\.(?:\s+(?=[A-Z])|$)", " ".join(text))[0])
            for name in (n.strip() for n in names.split(",")):
                docs[name] = (unit, sentence or name.replace("_", " "))
            continue
        k += 1
    return docs


def units_of(cls: type, names) -> dict[str, str]:
    """``{name: units}`` of the fields ``names`` of ``cls`` that have a unit (not ``"1"``)."""
    docs = field_docs(cls)
    return {name: docs[name][0] for name in names
            if name in docs and docs[name][0] != DIMENSIONLESS}  # fmt: skip


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
