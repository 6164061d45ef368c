"""Results kept on disk: one netCDF form for every result, and the reader of the old files.

- :mod:`.dataset`: a result dataclass as a labelled ``xarray.Dataset`` and back, field by field
  (a result inside a result, such as a run's :class:`~cable_ocp.simulation.trajectory.Trajectory`,
  included);
- :mod:`.units`: the fields' units, declared by each result class, and their long names;
- :mod:`.netcdf`: the one (atomic) writer and the reader of netCDF files, every result's and a
  sweep's, which checks a file before reading its data, and the format versions;
- :mod:`.format_1`: the npz + json files of cable_ocp 0.1.

:func:`save` and :func:`load` are the path every result takes.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import ClassVar

import xarray as xr

from cable_ocp.result_files import netcdf

SWEEP_FILE = "sweep.nc"  # a sweep folder's assembled cases (cable_ocp.sweep.store)
SWEEP_KIND = "SweepDataset"  # its kind, as the file declares it


def save(result, path: str | Path) -> Path:
    """Write ``result.to_xarray()`` to the netCDF file ``path``; returns the path."""
    return netcdf.write(result.to_xarray(), Path(path))


def result_file(path: str | Path, name: str) -> Path:
    """The file that a result's ``save(path)`` and ``load(path)`` mean.

    ``path`` itself if it names a ``.nc`` file, else the file ``name`` in the folder ``path``.
    """
    path = Path(path)
    return path if path.suffix == ".nc" else path / name


def load(cls: type, path: str | Path, what: str, check=None):
    """A ``cls`` read from the netCDF file ``path`` by ``cls.from_xarray``.

    Parameters
    ----------
    cls : result class
        Its name is the kind the file must hold.
    path : path-like
    what : str
        The result in words, for the error (``"trajectory"``).
    check : callable, optional
        ``check(result, dataset)`` raises ValueError if the result read does not fit what the
        file says of it (its figures, its scene).

    Raises
    ------
    ValueError
        Naming the file: it is missing, not a result of this kind or of a format this cable_ocp
        reads (:func:`.netcdf.read`), or its fields do not fit (``from_xarray``, ``check``).
    """
    path = Path(path)
    dataset = netcdf.read(path, cls.__name__)
    try:
        result = cls.from_xarray(dataset)
        if check is not None:
            check(result, dataset)
    except (ValueError, KeyError, TypeError) as error:
        raise ValueError(
            f"{path}: not a readable {what} ({type(error).__name__}: {error})"
        ) from None
    return result


def read_sweep(path: str | Path) -> xr.Dataset:
    """A sweep's Dataset, every case along ``case``, from its ``sweep.nc`` (loaded, file closed).

    A file that declares its kind is read and checked as every result is (:func:`.netcdf.read`);
    a sweep written before sweeps declared it (it carries the ``sweep_text`` attribute) is read
    as it is.

    Raises
    ------
    ValueError
        Naming the file: missing, unreadable, or not a sweep's.
    """
    path = Path(path)
    try:
        kind = netcdf.kind_of(path)
    except ValueError:
        kind = None
    if kind == SWEEP_KIND:
        return netcdf.read(path, SWEEP_KIND)
    if kind is not None:
        raise ValueError(f"{path}: holds a {kind}, not a sweep's cases")
    try:
        with xr.open_dataset(path) as dataset:
            if "sweep_text" not in dataset.attrs:
                raise ValueError("no attribute sweep_text")
            return dataset.load()
    except (OSError, ValueError) as error:
        raise ValueError(f"{path}: not a sweep's cases ({error})") from None


class KeptInFolder:
    """``save(path)`` and ``load(path)`` of a result kept as one file in a results folder.

    A result class sets ``FILE`` (its file's name in a folder, ``"result.nc"``), ``WHAT`` (the
    result in words, for errors) and ``FORMAT_1`` (the JSON file of cable_ocp 0.1 in a folder,
    with ``read_format_1(folder)``, its reader).
    """

    FILE: ClassVar[str]
    WHAT: ClassVar[str]
    FORMAT_1: ClassVar[str]
    read_format_1: ClassVar[Callable]

    def save(self, path: str | Path) -> Path:
        """Write the result to netCDF (``to_xarray``); returns the file's path.

        ``path`` is the file if it ends in ``.nc``, else a results folder that gets ``FILE``.
        """
        return save(self, result_file(path, self.FILE))

    @classmethod
    def load(cls, path: str | Path):
        """Read a result written by :meth:`save`, from its file or its results folder.

        A folder holds ``FILE``, or the files of cable_ocp 0.1 (``FORMAT_1`` beside them).

        Raises
        ------
        ValueError
            Naming the file, if a file of the result is missing, truncated or garbled.
        """
        file = result_file(path, cls.FILE)
        if not file.exists() and (file.parent / cls.FORMAT_1).exists():
            return cls.read_format_1(file.parent)
        return load(cls, file, cls.WHAT)
