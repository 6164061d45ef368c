"""A result dataclass as a labelled ``xarray.Dataset``, and back: each field by its type.

Every result a user keeps (a :class:`~cable_ocp.simulation.trajectory.Trajectory`, an
``OcpResult``, an ``MpcResult``) has one form: a Dataset with named dimensions (``time``,
``element``, ``joint``, ``component``, ...), coordinates, and CF-style ``units`` and ``long_name``
attributes on every variable (:mod:`.netcdf` writes it). The result modules state only what is
their own (dimension names, coordinates); this module turns the dataclass fields into variables
by their type, so a field added to a result is carried without code changes:

- a number or bool: a 0-d variable; an array, a list of numbers or a tuple: a variable with the
  dimensions named for it (``NAME_0``, ``NAME_1``, ... by default);
- ``dict[str, array]`` or ``dict[str, float]``: one variable over a dimension of the keys;
- a string: a global attribute; anything else (lists of strings, dicts): a global attribute
  holding JSON;
- a result inside the result (a dataclass with ``to_xarray`` and ``from_xarray``, such as the
  ``trajectory`` of an ``OcpResult`` or an ``MpcResult``): its own Dataset's variables and
  attributes joined to the outer ones, each whose name the outer result already uses prefixed
  by the field's name (``trajectory_omega``, ``solves_iterations``).

Units are those the class declares, long names its docstring's (:mod:`.units`).
"""

from __future__ import annotations

import json
import types
import typing
from collections.abc import Iterable, Mapping
from dataclasses import MISSING, fields, is_dataclass

import numpy as np
import xarray as xr

from cable_ocp.result_files.netcdf import GLOBAL, file_attributes
from cable_ocp.result_files.units import DIMENSIONLESS, describe, long_names, unit_of
from cable_ocp.scene.records import check_field, parse_json

COMPONENT = ("x", "y", "z")


def _hints(cls: type) -> dict[str, object]:
    return typing.get_type_hints(cls)


def _nested_class(hint) -> type | None:
    """The result class of a field holding a result (or None), ``Trajectory | None`` included."""
    options = typing.get_args(hint) if isinstance(hint, types.UnionType) else (hint,)
    for option in options:
        if isinstance(option, type) and is_dataclass(option) and hasattr(option, "from_xarray"):
            return option
    return None


def _kind_of(hint) -> str:
    """How a field of type ``hint`` is stored.

    One of number, array, sequence, mapping, text, nested (a result) or json.
    """
    origin, args = typing.get_origin(hint), typing.get_args(hint)
    if hint in (bool, int, float):
        return "number"
    if hint is np.ndarray:
        return "array"
    if hint is str:
        return "text"
    if _nested_class(hint) is not None:
        return "nested"
    if origin in (list, tuple) and args and all(a in (float, int, Ellipsis) for a in args):
        return "sequence"
    if origin is dict and len(args) == 2 and args[0] is str and args[1] in (float, np.ndarray):
        return "mapping"
    return "json"


def to_dataset(
    result,
    kind: str,
    dims: Mapping[str, tuple[str, ...]],
    coords: Mapping[str, Iterable] | None = None,
    units: Mapping[str, str] | None = None,
    skip: Iterable[str] = (),
) -> xr.Dataset:
    """The fields of a result dataclass as a Dataset (see the module docstring).

    Parameters
    ----------
    result : dataclass instance
    kind : str
        Its class name, kept in the attribute ``cable_ocp_result``.
    dims : dict of str to tuple of str
        Dimensions of a field's array (for a mapping: the keys' dimension, then the values').
    coords : dict of str to sequence, optional
        Labels of dimensions, e.g. ``{"component": ("x", "y", "z")}``.
    units : dict of str to str, optional
        Units that the class cannot declare (they depend on the instance); every other field
        stored as a variable takes the unit its class declares (:func:`.units.unit_of`).

    Raises
    ------
    ValueError
        A field stored as a variable whose unit is not declared, naming it.
    skip : names of fields left out (the caller adds them)
    """
    cls = type(result)
    names, hints = long_names(cls), _hints(cls)
    coords, units = dict(coords or {}), dict(units or {})
    variables: dict[str, xr.Variable] = {}
    attrs: dict[str, object] = file_attributes(kind)
    nested = []
    for f in fields(result):
        if f.name in skip:
            continue
        value, how = getattr(result, f.name), _kind_of(hints[f.name])
        if how == "nested":
            if value is not None:
                nested.append((f.name, value.to_xarray()))
            continue
        if how == "text":
            attrs[f.name] = value
            continue
        if how == "json":
            attrs[f.name] = json.dumps(value)
            continue
        if how == "mapping":
            key_dim, *value_dims = dims.get(f.name, (f"{f.name}_key",))
            keys = list(value)
            if key_dim in coords and list(coords[key_dim]) != keys:
                key_dim = f"{f.name}_key"  # another mapping holds other keys
            coords[key_dim] = keys
            data = np.array([value[k] for k in keys], dtype=float)
            if not keys:  # no values, so no value dimensions of known size
                value_dims = [f"{f.name}_{i}" for i in range(len(value_dims))]
                data = data.reshape((0,) * (1 + len(value_dims)))
            elif len(value_dims) != data.ndim - 1:
                value_dims = [f"{f.name}_{i}" for i in range(data.ndim - 1)]
            variables[f.name] = xr.Variable((key_dim, *value_dims), data)
        else:
            data = np.asarray(value)
            if how == "sequence":
                data = data.astype(float) if data.size == 0 else data
            default = tuple(f"{f.name}_{i}" for i in range(data.ndim))
            variables[f.name] = xr.Variable(dims.get(f.name, default), data)
        unit = units[f.name] if f.name in units else unit_of(cls, f.name)
        describe(variables[f.name], unit, names.get(f.name, f.name.replace("_", " ")))
    used = {d for v in variables.values() for d in v.dims}
    labels = {d: describe(xr.Variable(d, list(v)), DIMENSIONLESS, d.replace("_", " "))
              for d, v in coords.items() if d in used and d not in variables}  # fmt: skip
    dataset = xr.Dataset(variables, coords=labels, attrs=attrs)
    for name, inner in nested:
        dataset = _joined(dataset, inner, f"{name}_")
    return dataset


def _joined(outer: xr.Dataset, inner: xr.Dataset, prefix: str) -> xr.Dataset:
    """``outer`` with the variables and attributes of ``inner``, a name it uses prefixed."""
    taken = set(outer.variables) | set(outer.attrs)
    indexes = set(inner.indexes)
    clashes = [n for n in inner.variables if n in taken and n not in indexes]
    inner = inner.rename({n: prefix + n for n in clashes})
    joined = xr.merge([outer, inner], combine_attrs="override", join="exact")
    joined.attrs = dict(outer.attrs)
    for name, value in inner.attrs.items():
        if name not in GLOBAL:
            joined.attrs[prefix + name if name in taken else name] = value
    return joined


def _inner_view(dataset: xr.Dataset, prefix: str) -> xr.Dataset:
    """The Dataset of a result inside ``dataset``: its prefixed names back to its own."""
    renamed = {n: n[len(prefix) :] for n in dataset.variables if n.startswith(prefix)}
    view = dataset.drop_vars([n for n in renamed.values() if n in dataset.variables])
    view = view.rename(renamed)
    attrs = dict(dataset.attrs)
    for name in [n for n in attrs if n.startswith(prefix)]:
        attrs[name[len(prefix) :]] = attrs.pop(name)
    view.attrs = attrs
    return view


def from_dataset(cls: type, dataset: xr.Dataset, skip: Iterable[str] = ()) -> dict:
    """The field values of ``cls`` from a Dataset written by :func:`to_dataset`.

    Each value is checked against the type its field declares, by the checks of result format
    1 (:func:`cable_ocp.scene.records.check_field`; NaN is a float's null): a file edited to
    ``success = "yes"`` or ``iterations = 3.7`` is refused, not coerced. A field the file lacks
    takes its default (it was added after the file was written). A result inside the result is
    read by its class's ``from_xarray``; an optional one (``Trajectory | None``) is None when
    the file holds none of it (no variable of its first field).

    Raises
    ------
    ValueError
        Naming the field: one without a default is missing, or a value does not fit its type
        (the caller adds the file).
    """
    hints, values, missing = _hints(cls), {}, []
    for f in fields(cls):
        if f.name in skip:
            continue
        how = _kind_of(hints[f.name])
        if how == "nested":
            inner = _nested_class(hints[f.name])
            view = _inner_view(dataset, f"{f.name}_")
            first = fields(inner)[0].name
            if first in view.variables:
                try:
                    values[f.name] = inner.from_xarray(view)
                except ValueError as error:
                    raise ValueError(f"{f.name}: {error}") from None
            elif type(None) in typing.get_args(hints[f.name]):
                values[f.name] = None
            else:
                missing.append(f.name)
            continue
        held = dataset.attrs if how in ("text", "json") else dataset.variables
        if f.name in held:
            stored = _stored(dataset, f.name, hints[f.name])
            values[f.name] = check_field(f.name, stored, hints[f.name], nan=True)
        elif f.default is not MISSING:
            values[f.name] = f.default
        elif f.default_factory is not MISSING:
            values[f.name] = f.default_factory()
        else:
            missing.append(f.name)
    if missing:
        raise ValueError(f"missing field(s) {', '.join(missing)}")
    return values


def _stored(dataset: xr.Dataset, name: str, hint):
    """The field ``name`` (of type ``hint``) as stored, in Python's terms, to be checked."""
    how = _kind_of(hint)
    if how == "text":
        return dataset.attrs[name]
    if how == "json":
        text = dataset.attrs[name]
        if not isinstance(text, str):
            raise ValueError(f"{name} = {text!r:.40}: expected JSON text")
        try:
            return parse_json(text)
        except ValueError as error:
            raise ValueError(f"{name}: {error}") from None
    variable = dataset.variables[name]
    if how == "array":
        return variable.values
    if how == "mapping":
        if variable.ndim == 0:
            raise ValueError(f"{name} = {variable.values!r:.40}: expected values over keys")
        keys = [str(k) for k in dataset[name][variable.dims[0]].values]
        scalar = typing.get_args(hint)[1] is float
        data = [d.tolist() if scalar else d for d in variable.values]
        return dict(zip(keys, data, strict=True))
    return variable.values.tolist()  # a number, or a list for a sequence


def fields_equal(a, b) -> bool:
    """Whether two results hold identical values, field by field (NaN equal to NaN)."""
    if type(a) is not type(b):
        return False
    for f in fields(a):
        x, y = getattr(a, f.name), getattr(b, f.name)
        if not _equal(x, y):
            return False
    return True


def _equal(x, y) -> bool:
    if hasattr(x, "equals") and not isinstance(x, np.ndarray):
        return type(x) is type(y) and x.equals(y)
    if is_dataclass(x) and not isinstance(x, type):
        return fields_equal(x, y)
    if isinstance(x, dict):
        return isinstance(y, dict) and list(x) == list(y) and all(_equal(x[k], y[k]) for k in x)
    if isinstance(x, np.ndarray | float | list | tuple) and not isinstance(x, str):
        try:
            return np.array_equal(np.asarray(x), np.asarray(y), equal_nan=True) and type(x) is type(
                y
            )
        except TypeError:  # strings inside
            return x == y
    return type(x) is type(y) and x == y


__all__ = ["COMPONENT", "fields_equal", "from_dataset", "to_dataset"]
