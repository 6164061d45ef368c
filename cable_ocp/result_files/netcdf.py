"""Result files: a result's Dataset written to netCDF and read back, checked before it is read.

Versions of the file format (the global attribute ``cable_ocp_format``): 1 is the npz + json of
cable_ocp 0.1 (:mod:`.format_1`); 2 is netCDF; 3 is netCDF with a closed-loop run kept as its
plant's :class:`~cable_ocp.simulation.trajectory.Trajectory` and its solves, and every
objective history in m^2. This module writes 3 and reads 2 and 3 (each result's reader turns a
2 into the present fields).
"""

from __future__ import annotations

import json
import os
import secrets
import signal
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from importlib import metadata
from pathlib import Path

import numpy as np
import xarray as xr

FORMAT = 3
READ_FORMATS = (2, 3)
FORMATS = "1 (npz + json, cable_ocp 0.1), 2 and 3 (netCDF)"
KIND = "cable_ocp_result"
VERSION = "cable_ocp_format"
WRITER = "cable_ocp_version"
# Global attributes of every file, not fields of a result.
GLOBAL = (KIND, VERSION, WRITER, "Conventions")


def package_version() -> str:
    """The installed cable_ocp's version (``"unknown"`` outside an installation)."""
    try:
        return metadata.version("cable_ocp")
    except metadata.PackageNotFoundError:
        return "unknown"


def file_attributes(kind: str) -> dict[str, object]:
    """The global attributes of a result file holding a ``kind`` (its class name)."""
    return {KIND: kind, VERSION: FORMAT, WRITER: package_version(), "Conventions": "CF-1.10"}


def kind_of(path: Path) -> str:
    """The kind of result the file ``path`` holds (its class name), reading its attributes only.

    Files of line runs written before the result format carried their kind in
    ``cable_ocp_kind``.

    Raises
    ------
    ValueError
        Naming the file: it is missing, not netCDF, or not a cable_ocp result.
    """
    import netCDF4

    path = Path(path)
    if not path.is_file():
        raise ValueError(f"{path}: no such file")
    try:
        with netCDF4.Dataset(path) as stored:
            attrs = {name: stored.getncattr(name) for name in stored.ncattrs()}
    except OSError as error:
        detail = " ".join(str(error).split())[:160]
        raise ValueError(f"{path}: not a readable netCDF file ({detail})") from None
    kind = attrs.get(KIND, attrs.get("cable_ocp_kind"))
    if not isinstance(kind, str):
        raise ValueError(f"{path}: not a cable_ocp result (no attribute {KIND})")
    return kind


def written_here(dataset: xr.Dataset) -> bool:
    """Whether a Dataset read by :func:`read` was written by this version of cable_ocp."""
    return dataset.attrs.get(WRITER) == package_version()


def format_of(dataset: xr.Dataset) -> int:
    """The format a Dataset read by :func:`read` was written in."""
    return int(dataset.attrs[VERSION])


def write(
    dataset: xr.Dataset,
    path: Path,
    groups: dict[str, xr.Dataset] | None = None,
    mode: int | None = None,
) -> Path:
    """Write a result's Dataset to netCDF at ``path``, atomically, without Dask's scheduler lock.

    The one writer of netCDF files: every result's and a sweep's (its case files and
    ``sweep.nc``). ``groups`` are written beside it as netCDF groups by name (a line's
    segments); ``mode`` (permission bits) is set on the file, else the process's default. A
    folder of ``path`` that does not exist yet is made.
    Every variable of numbers must declare its ``units`` (CF; ``"1"`` for a count): one that
    does not is refused before anything is written (:func:`_check_units`).

    The file is written as a scratch file ``.NAME.XXXXXXXX.tmp`` beside ``path``, flushed to
    the disk (``fsync``) and renamed onto it, so ``path`` holds either its old content or the
    whole new file, even after a crash of the machine; on any exception, Ctrl-C included, the
    scratch file is removed. A Ctrl-C that arrives while netCDF4 writes is
    held until the part being written (the root, or a group) is written, then raised: an
    interrupt inside xarray's write leaves netCDF4's process-wide locks held, and the next close
    waits on them for ever. The file is opened once for all its parts (a line run of 100
    segments took 29 s reopened for each, 15 s opened once).

    A result's arrays are in memory, so they go straight to xarray's netCDF4 store under
    netCDF4's own locks: ``Dataset.to_netcdf`` first asks Dask for its scheduler, which imports
    ``dask.distributed`` (0.3 s of a ``cable-ocp simulate``), and in a sweep's worker would take
    the cluster's lock. The file is the one ``to_netcdf`` writes (same store, same encoding).
    """
    import netCDF4
    from xarray.backends import NetCDF4DataStore
    from xarray.backends.locks import HDF5_LOCK, NETCDFC_LOCK, combine_locks

    path = Path(path)
    parts = {None: dataset, **(groups or {})}
    for group, part in parts.items():
        if any(variable.chunks is not None for variable in part.variables.values()):
            raise ValueError(f"{path}: a result's arrays must be in memory, not Dask arrays")
        _check_units(part, f"{group}/" if group else "", path)
    lock = combine_locks([NETCDFC_LOCK, HDF5_LOCK])  # what to_netcdf takes, less Dask's
    path.parent.mkdir(parents=True, exist_ok=True)
    scratch = path.parent / f".{path.name}.{secrets.token_hex(4)}.tmp"
    try:
        with _interrupts_held() as interrupt_if_seen:
            with netCDF4.Dataset(scratch, mode="w", format="NETCDF4") as root:  # opened once
                for group, part in parts.items():
                    part.dump_to_store(NetCDF4DataStore(root, group=group, mode="a", lock=lock))
                    interrupt_if_seen()
        _flushed(scratch)
        if mode is not None:
            os.chmod(scratch, mode)
        os.replace(scratch, path)
    except RuntimeError as error:  # netCDF's "NetCDF: HDF error": a refused write
        size = scratch.stat().st_size if scratch.exists() else 0
        scratch.unlink(missing_ok=True)
        raise WriteFailed(str(error), path, size) from error
    except BaseException:
        scratch.unlink(missing_ok=True)
        raise
    return path


def _check_units(dataset: xr.Dataset, where: str, path: Path) -> None:
    """ValueError naming the first variable of numbers in ``dataset`` without ``units``.

    Booleans and text carry none; coordinates label a dimension (a sweep's swept values).
    """
    for name, variable in dataset.data_vars.items():
        if variable.dtype.kind in "iufc" and not variable.attrs.get("units"):
            raise ValueError(
                f"{path}: {where}{name} has no declared units (CF units, '1' for a count)"
            )


def _flushed(path: Path) -> None:
    """Flush the file ``path`` from the system's cache to the disk."""
    handle = os.open(path, os.O_RDONLY)
    try:
        os.fsync(handle)
    finally:
        os.close(handle)


class WriteFailed(RuntimeError):
    """netCDF's error (its message) writing ``path``, whose scratch file got to ``size`` bytes."""

    def __init__(self, message: str, path: Path, size: int):
        super().__init__(message)
        self.path, self.size = path, size


@contextmanager
def _interrupts_held() -> Iterator[Callable[[], None]]:
    """Hold SIGINT over a block; yields a function that delivers a held one (call it when safe).

    A held signal is delivered to the handler it was meant for (Python's: KeyboardInterrupt) at
    the next call of the yielded function, or when the block ends. Only the main thread
    receives signals; elsewhere, or where SIGINT has no Python handler (it is ignored, or the
    system's default ends the process), the block runs as it is.
    """
    previous = signal.getsignal(signal.SIGINT)
    if threading.current_thread() is not threading.main_thread() or not callable(previous):
        yield lambda: None
        return
    held: list[int] = []

    def deliver() -> None:
        if held:
            previous(held.pop(), None)

    signal.signal(signal.SIGINT, lambda number, frame: held.append(number))
    try:
        yield deliver
    finally:
        signal.signal(signal.SIGINT, previous)
    deliver()


# Deflate, the netCDF4 compression, packs at most about 1032 bytes into one: a file cannot hold
# more data than that many times its size.
DEFLATE_RATIO = 1032


def read(path: Path, kind: str, group: str | None = None) -> xr.Dataset:
    """A result's Dataset from ``path`` (or its ``group``), loaded into memory (file closed).

    :func:`read_groups` of one group, with its checks and errors.
    """
    return read_groups(path, kind, [group])[0]


def read_groups(path: Path, kind: str, groups: list[str | None]) -> list[xr.Dataset]:
    """The Datasets of the root (``None``) or groups of the file ``path``, the file opened once.

    Opening a file of many groups costs more than reading one (0.5 s a time for a line run of 100
    segments): a line run's segments are read in one call.

    Before any data is read, the file's declared contents are checked: its kind and format
    (:func:`_check_declared`), and, when the root is among ``groups``, over every group
    (:func:`_check_contents`) sizes that the file can hold, booleans stored as 0 or 1, and a line
    run's segments. A Ctrl-C while the data are read is raised between groups (see
    :func:`write`).

    Raises
    ------
    ValueError
        Naming the file: it is missing, unreadable, not a cable_ocp result of this kind, written
        in a newer format than this cable_ocp reads (with the versions), or declaring more data
        than it holds, or a field that does not fit.
    """
    import netCDF4
    from xarray.backends import NetCDF4DataStore
    from xarray.backends.store import StoreBackendEntrypoint

    path = Path(path)
    datasets = []
    try:
        with netCDF4.Dataset(path) as root:
            _check_declared({name: root.getncattr(name) for name in root.ncattrs()}, kind)
            if None in groups:
                _check_contents(root, path.stat().st_size)
            with _interrupts_held() as interrupt_if_seen:
                for group in groups:
                    store = NetCDF4DataStore(root, group=group, mode="r")
                    datasets.append(StoreBackendEntrypoint().open_dataset(store).load())
                    interrupt_if_seen()
    except FileNotFoundError:
        raise ValueError(f"{path}: no such file") from None
    except _Refused as error:
        raise ValueError(f"{path}: {error}") from None
    except (OSError, ValueError, KeyError, TypeError, RuntimeError) as error:
        detail = " ".join(str(error).split())[:160]
        raise ValueError(f"{path}: not a readable netCDF file ({detail})") from None
    return datasets


class _Refused(Exception):
    """A file that is netCDF but not a readable result (the message names the field)."""


def _check_declared(attrs: dict, kind: str) -> None:
    """Check the kind and format the file's global ``attrs`` declare; _Refused if it is bad."""
    found, version = attrs.get(KIND), attrs.get(VERSION)
    if found is None:
        raise _Refused(f"not a cable_ocp result (no attribute {KIND})")
    if found != kind:
        raise _Refused(f"holds a {found}, not a {kind}")
    if not isinstance(version, int | np.integer) or isinstance(version, bool | np.bool_):
        raise _Refused(f"{VERSION} = {version!r:.40}: expected an integer (the result format)")
    if version > FORMAT:
        writer = attrs.get(WRITER, "unknown")
        raise _Refused(
            f"written in result format {version} by cable_ocp {writer}; cable_ocp "
            f"{package_version()} reads formats {FORMATS}: install a newer cable_ocp"
        )
    if version not in READ_FORMATS:
        raise _Refused(
            f"{VERSION} = {version}: not a format of netCDF results (those are "
            f"{', '.join(map(str, READ_FORMATS))})"
        )


def _check_contents(stored, size: int) -> None:
    """Check every group of the open file ``stored`` against its ``size`` (bytes) and each other.

    _Refused if one is bad.

    Reads the groups' metadata and booleans only:

    - the data every group declares (root included) fits in the file's size (deflate packs at
      most :data:`DEFLATE_RATIO` bytes into one);
    - booleans are stored as 0 or 1 (xarray reads any byte as a bool);
    - a line run's root (attribute ``segments``): ``segments`` is the count of its groups
      ``segment_0 ..``, ``element_length`` is finite, positive and its scene's
      ``winch.line.element_length``, and every segment holds the same scene.
    """
    groups = {"": stored, **{f"{name}/": group for name, group in _groups(stored)}}
    declared = {where: _declared_bytes(group) for where, group in groups.items()}
    if sum(nbytes for nbytes, _ in declared.values()) > size:
        where = max(declared, key=lambda name: declared[name][0])
        raise _Refused(
            f"declares more data than its {size} bytes can hold ({where}"
            f"{declared[where][1]}): a damaged or forged file"
        )
    for where, group in groups.items():
        _check_booleans(group, where)
    if "segments" in stored.ncattrs():
        _check_segments(stored)


def _groups(group, prefix: str = ""):
    """(path, group) of every group below ``group``, depth first."""
    for name, child in group.groups.items():
        yield prefix + name, child
        yield from _groups(child, f"{prefix}{name}/")


def _declared_bytes(group) -> tuple[float, str]:
    """Bytes a netCDF4 group's variables declare, and its largest variable (for the message).

    A packed (compressed) variable counts at the best ratio, :data:`DEFLATE_RATIO`.
    """
    total, largest, most = 0.0, "", -1.0
    for name, variable in group.variables.items():
        itemsize = variable.dtype.itemsize if isinstance(variable.dtype, np.dtype) else 8
        nbytes = float(np.prod(variable.shape, dtype=float)) * itemsize
        filters = variable.filters() or {}
        packed = any(filters.get(f) for f in ("zlib", "szip", "zstd", "bzip2", "blosc"))
        total += nbytes / DEFLATE_RATIO if packed else nbytes
        if nbytes > most:
            shape = dict(zip(variable.dimensions, variable.shape, strict=True))
            largest, most = f"{name} over {shape}", nbytes
    return total, largest


def _check_booleans(group, where: str) -> None:
    for name, variable in group.variables.items():
        if "dtype" in variable.ncattrs() and variable.getncattr("dtype") == "bool":
            variable.set_auto_maskandscale(False)
            values = np.asarray(variable[...])
            if not np.isin(values, (0, 1)).all():
                shown = values.tolist()
                raise _Refused(f"{where}{name} = {shown!r:.40}: expected true or false (0 or 1)")


def _check_segments(stored) -> None:
    """A line run's root attributes against its groups and their scenes (see _check_contents)."""
    count = _plain(stored.getncattr("segments"))
    names = sorted(stored.groups)
    expected = [f"segment_{k}" for k in range(len(names))]
    if (
        not isinstance(count, int | np.integer)
        or isinstance(count, bool | np.bool_)
        or count < 1
        or count != len(names)
        or names != sorted(expected)
    ):
        raise _Refused(
            f"segments = {count!r:.40}: expected the number of its groups segment_0 .. "
            f"segment_{max(len(names) - 1, 0)} ({len(names)}, at least 1)"
        )
    scenes = {
        name: group.getncattr("scene_record") if "scene_record" in group.ncattrs() else ""
        for name, group in ((name, stored.groups[name]) for name in expected)
    }
    first = scenes["segment_0"]
    for name, record in scenes.items():
        if record != first:
            field = _first_difference(_parsed(first), _parsed(record)) or "its scene_record"
            raise _Refused(
                f"{name}: its scene differs from segment_0's ({field}); a line run's segments "
                "all hold the run's one scene"
            )
    length = (
        _plain(stored.getncattr("element_length")) if "element_length" in stored.ncattrs() else None
    )
    if not isinstance(length, float | int | np.floating | np.integer) or not (
        np.isfinite(length) and length > 0
    ):
        raise _Refused(f"element_length = {length!r:.40}: expected a finite length > 0, m")
    winch = _parsed(first).get("winch")
    line = winch.get("line") if isinstance(winch, dict) else None
    scene_length = line.get("element_length") if isinstance(line, dict) else None
    known = isinstance(scene_length, float | int) and not isinstance(scene_length, bool)
    if known and not np.isclose(length, scene_length, rtol=1e-12, atol=0):
        raise _Refused(
            f"element_length = {float(length):g} m: its scene's winch.line.element_length is "
            f"{scene_length:g} m"
        )


def _plain(value):
    """A numpy scalar attribute as the Python number it holds (for messages)."""
    return value.item() if isinstance(value, np.generic) else value


def _parsed(record: str) -> dict:
    """A scene record (JSON text) as a dict; {} if it is not one."""
    try:
        value = json.loads(record) if record else {}
    except ValueError:
        return {}
    return value if isinstance(value, dict) else {}


def _first_difference(a: dict, b: dict, prefix: str = "") -> str:
    """The dotted name of the first field where two scene records differ."""
    for key in sorted(set(a) | set(b)):
        left, right = a.get(key), b.get(key)
        if isinstance(left, dict) and isinstance(right, dict):
            found = _first_difference(left, right, f"{prefix}{key}.")
            if found:
                return found
        elif left != right:
            return f"{prefix}{key}: {left!r:.30} against {right!r:.30}"
    return ""
