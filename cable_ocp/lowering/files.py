"""The lowering's results as netCDF files: one layout for a result that holds other results.

A :class:`~.plan.LandingPlan`, :class:`~.landing.LandingResult` or :class:`~.hold.HoldResult`
keeps at the file's root its own numbers and words
(:func:`cable_ocp.result_files.dataset.to_dataset`, as every result does) and its scene as
``scene_record`` (JSON, :meth:`Scene.to_dict`). Each result it holds is a netCDF group of its
own, named for its field and written by that result's own ``to_xarray``: a verified line run as
the group ``run`` (its whole-run views) with its segments in ``run/segment_K``, an
``OcpResult`` or ``MpcResult``, a report, a descent. The root's attribute ``parts`` lists the
groups; each group's ``cable_ocp_result`` says what it holds, which must be what its field's
type allows.

So nothing is prefixed or merged, a part may be absent (a failed run, no report), and a field of
either of two kinds (``LandingResult.result``: an optimum or a closed loop) is read by its kind.
"""

from __future__ import annotations

import json
import types
import typing
from collections.abc import Iterable
from dataclasses import asdict, fields, is_dataclass
from pathlib import Path

import numpy as np
import xarray as xr

from cable_ocp.result_files import dataset, netcdf
from cable_ocp.scene.records import check_field, parse_json
from cable_ocp.scene.schema import scene_of
from cable_ocp.simulation.line_trajectory import LineTrajectory
from cable_ocp.simulation.trajectory import Trajectory, check_recorded

PARTS = "parts"  # the root's attribute that lists the groups
SCENE = "scene_record"


def own_dataset(result, skip: Iterable[str] = (), dims=None) -> xr.Dataset:
    """A result's own fields as a Dataset, its tables of records (:func:`records_text`) too.

    ``skip`` are fields left out (its parts and its scene), ``dims`` the dimensions of its
    arrays (:func:`~cable_ocp.result_files.dataset.to_dataset`).
    """
    tables = _tables(type(result))
    own = dataset.to_dataset(result, type(result).__name__, dims or {}, skip=(*skip, *tables))
    own.attrs |= {name: records_text(getattr(result, name)) for name in tables}
    return own


def own_fields(cls: type, data: xr.Dataset, skip: Iterable[str] = ()) -> dict:
    """The field values of ``cls`` that :func:`own_dataset` wrote; ValueError if they do not fit."""
    tables = _tables(cls)
    values = dataset.from_dataset(cls, data, skip=(*skip, *tables))
    for name, record in tables.items():
        if name not in data.attrs:
            raise ValueError(f"missing field {name}")
        values[name] = records_of(data.attrs[name], record, name)
    return values


def records_text(records: tuple) -> str:
    """Records (dataclasses of numbers, bools and text) as a JSON list of objects.

    A global attribute: a record such as a :class:`~.checks.Check` holds its figures in a unit
    of its own (its ``unit``), which no variable's single CF unit could state.
    """
    return json.dumps([asdict(record) for record in records])


def records_of(text, cls: type, name: str) -> tuple:
    """The records of ``cls`` in the text of :func:`records_text`; ValueError naming the field."""
    items = parse_json(text) if isinstance(text, str) else None
    if not isinstance(items, list) or not all(isinstance(item, dict) for item in items):
        raise ValueError(f"{name} = {text!r:.40}: expected a JSON list of {cls.__name__} records")
    hints, own = typing.get_type_hints(cls), [f.name for f in fields(cls)]
    records = []
    for k, item in enumerate(items):
        if sorted(item) != sorted(own):
            raise ValueError(f"{name}[{k}]: expected the keys {', '.join(own)}")
        records.append(cls(**{f: check_field(f"{name}[{k}].{f}", item[f], hints[f], nan=True)
                              for f in own}))  # fmt: skip
    return tuple(records)


def _tables(cls: type) -> dict[str, type]:
    """The fields of ``cls`` holding tables of records (``tuple[Record, ...]``), and the record."""
    tables = {}
    for name, hint in typing.get_type_hints(cls).items():
        args = typing.get_args(hint)
        if typing.get_origin(hint) is tuple and len(args) == 2 and args[1] is Ellipsis:
            if is_dataclass(args[0]):
                tables[name] = args[0]
    return tables


def to_xarray(result, parts: Iterable[str], dims=None) -> xr.Dataset:
    """The root of a result's file: its own fields, its scene, and the names of its parts.

    Parameters
    ----------
    result : dataclass
        With a ``scene`` field.
    parts : iterable of str
        Its fields that hold results (written as groups by :func:`save`).
    dims : mapping, optional
        Dimension names of its own arrays (:func:`~cable_ocp.result_files.dataset.to_dataset`).
    """
    parts = tuple(parts)
    root = own_dataset(result, (*parts, "scene"), dims)
    root.attrs[SCENE] = json.dumps(result.scene.to_dict())
    root.attrs[PARTS] = json.dumps([name for name in parts if getattr(result, name) is not None])
    return root


def save(result, path: str | Path) -> Path:
    """Write ``result.to_xarray()`` and its parts' groups to the netCDF file ``path``."""
    root = result.to_xarray()
    groups = {}
    for name in parse_json(root.attrs[PARTS]):
        part = getattr(result, name)
        groups[name] = part.to_xarray()
        if isinstance(part, LineTrajectory):
            groups |= {_segment(name, k): s.to_xarray() for k, s in enumerate(part.segments)}
    return netcdf.write(root, Path(path), groups)


def load(cls: type, path: str | Path, what: str):
    """A ``cls`` read from the file ``path`` that :func:`save` wrote.

    Parameters
    ----------
    cls : the result's class
        Its name is the kind the file must hold; its ``PARTS`` the fields held as groups.
    path : path-like
    what : str
        The result in words, for the error.

    Raises
    ------
    ValueError
        Naming the file: missing, not a ``cls``, of a newer format, a field or part that does
        not fit (a part of another kind than its field allows included), or figures its runs do
        not give (``cls.check_file``: a forged file).
    """
    path = Path(path)
    kind = cls.__name__
    try:
        root = netcdf.read(path, kind)
        names = _names(root)
        hints = typing.get_type_hints(cls)
        parts = cls.PARTS
        unknown = sorted(set(names) - set(parts))
        if unknown:
            raise ValueError(f"{PARTS}: {', '.join(unknown)} is not a part of a {kind}")
        groups = _groups(path, kind, names)
        values = own_fields(cls, root, (*parts, "scene"))
        values["scene"] = scene_of(parse_json(root.attrs[SCENE]), f"the {what}'s")
        for name in parts:
            values[name] = _part(name, groups, hints[name]) if name in names else None
        result = cls(**values)
        result.check_file()
        return result
    except (ValueError, KeyError, TypeError) as error:
        detail = str(error).removeprefix(f"{path}: ")
        raise ValueError(f"{path}: not a readable {what} ({detail})") from None


def _names(root: xr.Dataset) -> list[str]:
    names = parse_json(root.attrs[PARTS]) if PARTS in root.attrs else None
    if not isinstance(names, list) or not all(isinstance(n, str) for n in names):
        raise ValueError(f"{PARTS} = {root.attrs.get(PARTS)!r:.60}: expected a JSON list of names")
    return names


def _groups(path: Path, kind: str, names: list[str]) -> dict[str, xr.Dataset]:
    """The parts' groups, then the segments of each that is a line run (``segments``)."""
    groups = dict(zip(names, netcdf.read_groups(path, kind, names), strict=True))
    segments = []
    for name in names:
        if "segments" in groups[name].attrs:
            count = groups[name].attrs["segments"]
            if not isinstance(count, int | np.integer) or isinstance(count, bool) or count < 1:
                raise ValueError(f"{name}: segments = {count!r:.40}: expected an integer >= 1")
            segments += [_segment(name, k) for k in range(int(count))]
    if segments:
        groups |= dict(zip(segments, netcdf.read_groups(path, kind, segments), strict=True))
    return groups


def _segment(name: str, k: int) -> str:
    """The group of segment ``k`` of the line run kept as the part ``name``."""
    return f"{name}/segment_{k}"


def _part(name: str, groups: dict[str, xr.Dataset], hint) -> object:
    """The result the group ``name`` holds, of a class its field's type ``hint`` allows."""
    group = groups[name]
    found = group.attrs.get(netcdf.KIND)
    allowed = {cls.__name__: cls for cls in _classes(hint)}
    if found not in allowed:
        raise ValueError(f"{name}: holds a {found}, expected {' or '.join(allowed)}")
    cls = allowed[found]
    try:
        if cls is LineTrajectory:
            return _line_run(name, group, groups)
        return cls.from_xarray(group)
    except (ValueError, KeyError, TypeError) as error:
        raise ValueError(f"{name}: {error}") from None


def _line_run(name: str, head: xr.Dataset, groups: dict[str, xr.Dataset]) -> LineTrajectory:
    """The line run of the part ``name`` and its segments' groups, checked as a line run file."""
    count, length = int(head.attrs["segments"]), float(head.attrs["element_length"])
    if not (np.isfinite(length) and length > 0):
        raise ValueError(f"element_length = {length!r}: expected a finite length > 0, m")
    segments = [Trajectory.from_xarray(groups[_segment(name, k)]) for k in range(count)]
    run = LineTrajectory(segments, length)
    check_recorded(run, run.time, run.clearance_error, None)
    return run


def _classes(hint) -> tuple[type, ...]:
    """The result classes a field of type ``hint`` holds (none for a plain field)."""
    options = typing.get_args(hint) if isinstance(hint, types.UnionType) else (hint,)
    return tuple(
        option
        for option in options
        if isinstance(option, type) and (hasattr(option, "from_xarray") or option is LineTrajectory)
    )


def check_landing_scene(scene, record: dict, part: str) -> None:
    """Check that a landing's ``scene`` has ``[lowering]`` and is the one its ``part`` ran on.

    ``record`` is the part's scene record (``{}`` when the part kept no run).

    Raises
    ------
    ValueError
        Naming ``scene_record`` and the part.
    """
    if scene.lowering is None:
        raise ValueError(f"{SCENE}: scene {scene.name!r} has no [lowering] table: not a landing's")
    if record and scene.to_dict() != record:
        raise ValueError(f"{SCENE}: scene {scene.name!r} is not the scene its {part} ran on")


def check_recomputed(name: str, stored, recomputed) -> None:
    """Check a stored figure (a number, a record, a table of them) against what its run gives.

    Numbers agree to a relative ``1e-9`` (or ``1e-12`` in their unit), NaN with NaN; text and
    flags exactly; records and tables field by field.

    Raises
    ------
    ValueError
        Naming the first field (``name.field[k]...``) that differs, its value and the run's.
    """
    if is_dataclass(stored) and type(stored) is type(recomputed):
        for f in fields(stored):
            check_recomputed(
                f"{name}.{f.name}", getattr(stored, f.name), getattr(recomputed, f.name)
            )
        return
    if isinstance(stored, tuple) and isinstance(recomputed, tuple):
        if len(stored) != len(recomputed):
            raise ValueError(f"{name}: {len(stored)} entries: its run gives {len(recomputed)}")
        for k, (a, b) in enumerate(zip(stored, recomputed, strict=True)):
            check_recomputed(f"{name}[{k}]", a, b)
        return
    if isinstance(stored, float | np.floating) and not isinstance(recomputed, bool):
        same = np.isclose(stored, recomputed, rtol=1e-9, atol=1e-12) or (
            np.isnan(stored) and np.isnan(recomputed)
        )
    else:
        same = stored == recomputed
    if not same:
        raise ValueError(f"{name} = {stored!r}: its run gives {recomputed!r}")


class Flat:
    """``to_xarray`` and ``from_xarray`` of a small result: numbers, arrays and tables of records.

    Its arrays' dimensions are the class's ``DIMS`` (field name to dimension names).
    """

    DIMS: typing.ClassVar[dict[str, tuple[str, ...]]] = {}

    def to_xarray(self) -> xr.Dataset:
        """The fields as a Dataset (:func:`own_dataset`)."""
        return own_dataset(self, dims=self.DIMS)

    @classmethod
    def from_xarray(cls, data: xr.Dataset):
        """The result a Dataset of :meth:`to_xarray` holds; ValueError if it does not fit."""
        return cls(**own_fields(cls, data))


class WithParts:
    """``to_xarray``, ``save(path)`` and ``load(path)`` of a result holding other results.

    The class names its parts (``PARTS``, fields holding results), the dimensions of its own
    arrays (``DIMS``) and itself in words (``WHAT``); the file is this module's layout.
    """

    PARTS: typing.ClassVar[tuple[str, ...]] = ()
    DIMS: typing.ClassVar[dict[str, tuple[str, ...]]] = {}
    WHAT: typing.ClassVar[str] = "result"

    def to_xarray(self) -> xr.Dataset:
        """The file's root: the result's own fields, its scene and its parts' names.

        The parts are written as groups by :meth:`save` (module docstring).
        """
        return to_xarray(self, self.PARTS, self.DIMS)

    def save(self, path: str | Path) -> Path:
        """Write the result and its parts to the netCDF file ``path``; returns the path."""
        return save(self, path)

    def check_file(self) -> None:
        """Check a result read by :meth:`load` against the runs it holds (none here).

        A kind whose figures its runs give (its scene, its report) checks them here
        (:func:`check_landing_scene`, :func:`check_recomputed`).

        Raises
        ------
        ValueError
            Naming the field that its runs do not give (a forged file).
        """

    @classmethod
    def load(cls, path: str | Path):
        """Read a result written by :meth:`save`.

        Raises
        ------
        ValueError
            Naming the file, if it is missing, not of this kind, damaged or does not fit.
        """
        return load(cls, path, cls.WHAT)
