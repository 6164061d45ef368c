"""Results as labelled data: a result dataclass as an ``xarray.Dataset``, kept in netCDF.

Every result a user keeps (a :class:`~cable_ocp.simulation.trajectory.Trajectory`, an
``OcpResult``, an ``MpcResult``) has one form: a Dataset with named dimensions (``time``,
``element``, ``joint``, ``component``, ...), coordinates, and CF-style ``units`` and ``long_name``
attributes on every variable, written to netCDF. The result modules state only what is their
own (dimension names, coordinates); this module turns the dataclass fields into variables by
their type, so a field added to a result is carried without code changes:

- a number or bool: a 0-d variable; an array, a list of numbers or a tuple: a variable with the
  dimensions named for it (``NAME_0``, ``NAME_1``, ... by default);
- ``dict[str, array]`` or ``dict[str, float]``: one variable over a dimension of the keys;
- a string: a global attribute; anything else (lists of strings, dicts): a global attribute
  holding JSON.

Units and long names come from the class docstring's ``Attributes`` section
(``name : float, m`` and the first sentence below it): written once, beside the field.

File format versions (the global attribute ``cable_ocp_format``): 1 is the npz + json form of
cable_ocp 0.1 (still read by each result's loader); 2 is netCDF, written by this module.
"""

from __future__ import annotations

import inspect
import json
import re
import typing
from collections.abc import Iterable, Mapping
from dataclasses import MISSING, fields
from functools import cache
from importlib import metadata
from pathlib import Path

import numpy as np
import xarray as xr

from cable_ocp.scene.records import check_field, parse_json

FORMAT = 2
FORMATS = "1 (npz + json, cable_ocp 0.1) and 2 (netCDF)"
KIND = "cable_ocp_result"
VERSION = "cable_ocp_format"
WRITER = "cable_ocp_version"
COMPONENT = ("x", "y", "z")
DIMENSIONLESS = "1"


def package_version() -> str:
    """The installed cable_ocp's version (``"unknown"`` outside an installation)."""
    try:
        return metadata.version("cable_ocp")
    except metadata.PackageNotFoundError:
        return "unknown"


# --- units and long names from the docstring ------------------------------------------------------


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


UNIT = re.compile(r"^[A-Za-z][A-Za-z0-9^/ ·-]*$")
NOT_UNITS = {"optional", "rad or m"}


@cache
def field_docs(cls: type) -> dict[str, tuple[str, str]]:
    """``{field: (units, long_name)}`` from the numpydoc ``Attributes`` section of ``cls``.

    A field documented without a unit gets ``"1"``; one not documented, ``"1"`` and its name.
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


# --- dataclass <-> Dataset ---------------------------------------------------------------------


def _hints(cls: type) -> dict[str, object]:
    return typing.get_type_hints(cls)


def _kind_of(hint) -> str:
    """How a field of type ``hint`` is stored: number, array, sequence, mapping, text or json."""
    origin, args = typing.get_origin(hint), typing.get_args(hint)
    if hint in (bool, int, float):
        return "number"
    if hint is np.ndarray:
        return "array"
    if hint is str:
        return "text"
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
        Units that the docstring cannot state (they depend on the instance).
    skip : names of fields left out (the caller adds them)
    """
    docs, hints = field_docs(type(result)), _hints(type(result))
    coords, units = dict(coords or {}), dict(units or {})
    variables: dict[str, xr.Variable] = {}
    attrs: dict[str, object] = {KIND: kind, VERSION: FORMAT, WRITER: package_version(),
                                "Conventions": "CF-1.10"}  # fmt: skip
    for f in fields(result):
        if f.name in skip:
            continue
        value, how = getattr(result, f.name), _kind_of(hints[f.name])
        unit, long_name = docs.get(f.name, (DIMENSIONLESS, f.name.replace("_", " ")))
        unit = units.get(f.name, unit)
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
        describe(variables[f.name], unit, long_name)
    used = {d for v in variables.values() for d in v.dims}
    labels = {d: describe(xr.Variable(d, list(v)), DIMENSIONLESS, d.replace("_", " "))
              for d, v in coords.items() if d in used and d not in variables}  # fmt: skip
    return xr.Dataset(variables, coords=labels, attrs=attrs)


def from_dataset(cls: type, dataset: xr.Dataset, skip: Iterable[str] = ()) -> dict:
    """The field values of ``cls`` from a Dataset written by :func:`to_dataset`.

    Each value is checked against the type its field declares, by the checks of result format
    1 (:func:`cable_ocp.scene.records.check_field`; NaN is a float's null): a file edited to
    ``success = "yes"`` or ``iterations = 3.7`` is refused, not coerced. A field the file lacks
    takes its default (it was added after the file was written).

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


# --- files -------------------------------------------------------------------------------------


def write(dataset: xr.Dataset, path: Path) -> Path:
    """Write a result's Dataset to netCDF at ``path``, without any Dask scheduler's lock.

    A result's arrays are in memory, so they go straight to xarray's netCDF4 store under
    netCDF4's own locks: ``Dataset.to_netcdf`` first asks Dask for its scheduler, which imports
    ``dask.distributed`` (0.3 s of a ``cable-ocp simulate``), and in a sweep's worker would take
    the cluster's lock. The file is the one ``to_netcdf`` writes (same store, same encoding).
    """
    from xarray.backends import NetCDF4DataStore
    from xarray.backends.locks import HDF5_LOCK, NETCDFC_LOCK, combine_locks

    path = Path(path)
    if any(variable.chunks is not None for variable in dataset.variables.values()):
        raise ValueError(f"{path}: a result's arrays must be in memory, not Dask arrays")
    lock = combine_locks([NETCDFC_LOCK, HDF5_LOCK])  # what to_netcdf takes, less Dask's
    store = NetCDF4DataStore.open(path, mode="w", format="NETCDF4", lock=lock)
    try:
        dataset.dump_to_store(store)
    finally:
        store.close()
    return path


# Deflate, the netCDF4 compression, packs at most about 1032 bytes into one: a file cannot hold
# more data than that many times its size.
DEFLATE_RATIO = 1032


def read(path: Path, kind: str) -> xr.Dataset:
    """A result's Dataset from ``path``, loaded into memory (the file is closed).

    Before any data is read, the file's declared contents are checked (:func:`_check_declared`):
    its kind and format, sizes that the file can hold, booleans stored as 0 or 1.

    Raises
    ------
    ValueError
        Naming the file: it is missing, unreadable, not a cable_ocp result of this kind, written
        in a newer format than this cable_ocp reads (with the versions), or declaring more data
        than it holds, or a field that does not fit.
    """
    path = Path(path)
    try:
        with xr.open_dataset(path, decode_cf=False) as raw:
            _check_declared(path, raw, kind)
        with xr.open_dataset(path) as dataset:
            dataset = dataset.load()
    except FileNotFoundError:
        raise ValueError(f"{path}: no such file") from None
    except _Refused as error:
        raise ValueError(f"{path}: {error}") from None
    except (OSError, ValueError, KeyError, TypeError, RuntimeError) as error:
        detail = " ".join(str(error).split())[:160]
        raise ValueError(f"{path}: not a readable netCDF file ({detail})") from None
    return dataset


class _Refused(Exception):
    """A file that is netCDF but not a readable result (the message names the field)."""


def _check_declared(path: Path, raw: xr.Dataset, kind: str) -> None:
    """Check what the file declares, reading no more than its booleans; _Refused if it is bad."""
    found, version = raw.attrs.get(KIND), raw.attrs.get(VERSION)
    if found is None:
        raise _Refused(f"not a cable_ocp result (no attribute {KIND})")
    if found != kind:
        raise _Refused(f"holds a {found}, not a {kind}")
    if not isinstance(version, int | np.integer) or isinstance(version, bool | np.bool_):
        raise _Refused(f"{VERSION} = {version!r:.40}: expected an integer (the result format)")
    if version > FORMAT:
        writer = raw.attrs.get(WRITER, "unknown")
        raise _Refused(
            f"written in result format {version} by cable_ocp {writer}; cable_ocp "
            f"{package_version()} reads formats {FORMATS}: install a newer cable_ocp"
        )
    if version != FORMAT:
        raise _Refused(f"{VERSION} = {version}: not a format of netCDF results (that is {FORMAT})")
    size = path.stat().st_size
    declared = 0.0
    for variable in raw.variables.values():
        nbytes = float(np.prod(variable.shape, dtype=float)) * variable.dtype.itemsize
        packed = variable.encoding.get("zlib") or variable.encoding.get("compression")
        declared += nbytes / DEFLATE_RATIO if packed else nbytes
    if declared > size:
        largest = max(raw.variables, key=lambda name: raw.variables[name].size)
        shape = dict(zip(raw.variables[largest].dims, raw.variables[largest].shape, strict=True))
        raise _Refused(
            f"declares more data than its {size} bytes can hold ({largest} over {shape}): "
            "a damaged or forged file"
        )
    booleans = [name for name, variable in raw.variables.items() if variable.dtype == bool]
    if booleans:  # xarray reads any byte as a bool: the stored bytes, from netCDF4 itself
        import netCDF4

        with netCDF4.Dataset(path) as stored:
            for name in booleans:
                variable = stored[name]
                variable.set_auto_maskandscale(False)
                values = np.asarray(variable[...])
                if not np.isin(values, (0, 1)).all():
                    shown = values.tolist()
                    raise _Refused(f"{name} = {shown!r:.40}: expected true or false (0 or 1)")


__all__ = [
    "COMPONENT", "FORMAT", "describe", "field_docs", "fields_equal", "from_dataset", "read",
    "to_dataset", "write",
]  # fmt: skip
