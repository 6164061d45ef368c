"""The numbers of a model as an input vector ``p``: one symbolic model per structure.

A :class:`~cable_ocp.model.cable.ModelSpec` mixes structure (``n``, torsion, which forces act, the
quadrature) with numbers (length, densities, coefficients, current, stiffnesses, Baumgarte gains).
:func:`structure_of` keeps the structure and replaces every number by a marker;
:func:`symbolic_spec` puts an element of an SX vector ``p`` in each marked place, so that the model
built from it takes the numbers as an input, and every spec of one structure shares its symbolic
model and its compiled libraries (a sweep over 20 currents compiles once). :func:`parameter_values`
gives the ``p`` of a spec.

A number that is zero stays a structural zero (a force switched off is not computed at all), except
the current (uniform or the profile's rows), which is always a parameter: still water and a
current are the same structure.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any

import casadi as ca
import numpy as np

# Numbers that are parameters even when zero (a field of this name anywhere in the spec).
ALWAYS_PARAMETERS = ("current", "current_z", "current_u", "current_v")
# What a parameter's place holds in a structure: any non-zero number would do.
MARKER = 1.0


def is_on(value: float | ca.SX) -> bool:
    """Whether a term with this coefficient exists: a positive number or a parameter (symbolic)."""
    return isinstance(value, ca.SX) or value > 0


def _is_parameter(name: str, value: float) -> bool:
    return name in ALWAYS_PARAMETERS or value != 0


def _map_numbers(obj: Any, leaf: Callable[[str, str, float], Any], path: str = "") -> Any:
    """Rebuild a tree of frozen dataclasses with every ``float`` field (or tuple of floats) mapped.

    ``leaf(path, field_name, value)`` gives the new value; fields of other types are kept (ints
    and bools are structure). Fields are visited in declaration order, so the order is stable.
    """
    changes = {}
    for item in dataclasses.fields(obj):
        value = getattr(obj, item.name)
        where = f"{path}{item.name}"
        if dataclasses.is_dataclass(value):
            changes[item.name] = _map_numbers(value, leaf, f"{where}.")
        elif item.type == "float":
            changes[item.name] = leaf(where, item.name, value)
        elif item.type.startswith("tuple[float"):
            changes[item.name] = tuple(
                leaf(f"{where}[{k}]", item.name, v) for k, v in enumerate(value)
            )
    return dataclasses.replace(obj, **changes)


def structure_of(spec: Any) -> Any:
    """The spec with each parameter replaced by :data:`MARKER` (structural zeros kept).

    Two specs have equal structures exactly when one symbolic model serves both.
    """
    return _map_numbers(spec, lambda _, name, value: MARKER if _is_parameter(name, value) else 0.0)


def _parameters(spec: Any) -> list[tuple[str, float]]:
    """``(dotted path, value)`` of each parameter, in the order of ``p``."""
    found: list[tuple[str, float]] = []

    def collect(path: str, name: str, value: float) -> float:
        if _is_parameter(name, value):
            found.append((path, float(value)))
        return value

    _map_numbers(spec, collect)
    return found


def parameter_names(spec: Any) -> list[str]:
    """Dotted paths of the parameters, in the order of ``p`` (e.g. ``element.hydro.current[1]``)."""
    return [path for path, _ in _parameters(spec)]


def parameter_values(spec: Any) -> np.ndarray:
    """The vector ``p`` of a spec (its numbers, in :func:`parameter_names` order)."""
    return np.array([value for _, value in _parameters(spec)])


def symbolic_spec(structure: Any) -> tuple[Any, ca.SX]:
    """The structure with an element of a new SX vector ``p`` in place of each parameter.

    Returns
    -------
    spec : the structure's type, holding SX scalars where the numbers were
    p : SX (count, 1)
    """
    count = len(parameter_names(structure))
    p = ca.SX.sym("p", count)
    position = iter(range(count))

    def place(_: str, name: str, value: float) -> ca.SX | float:
        return p[next(position)] if _is_parameter(name, value) else 0.0

    return _map_numbers(structure, place), p
