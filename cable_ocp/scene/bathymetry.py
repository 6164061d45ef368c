"""Bathymetry grids: the seabed's absolute elevation on a regular grid, read and checked once.

A grid file holds the elevation z (m, up, the sea surface at z = 0) over local metric coordinates
x, y (m), in the scene's frame (CONVENTIONS.md §3):

- **netCDF** (``.nc``): a 2-D variable (``seabed.grid.variable``, default ``elevation``) over the
  coordinates ``x`` and ``y``, in either order; each axis strictly monotone (a decreasing one is
  flipped); a ``units`` attribute, where given, is metres;
- **CSV** (``.csv``): columns x, y, z (an optional header line; ``#`` comments; UTF-8, with or
  without the byte-order mark of an Excel export), one row per grid point in any order, every
  (x, y) of the grid exactly once.

A grid whose spline cannot fit in the memory available (:data:`GRID_BYTES_PER_POINT` a point) is
refused before its data are read.

Each axis needs :data:`MIN_AXIS_POINTS` points (a cubic B-spline). Every problem is a
:class:`GridError` naming the file and, where there is one, the point; the scene turns it into a
``SceneError`` on ``seabed.grid.file`` when the scene is loaded, before any symbolic work. Grids are
read once per file version (path, size and modification time).
"""

from __future__ import annotations

import functools
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

MIN_AXIS_POINTS = 4  # a cubic B-spline needs four points along each axis
METRES = ("m", "metre", "metres", "meter", "meters")
# Memory a grid point costs once its spline and the spline's first and second derivatives are
# built (measured 164 B at 800 x 800 and 1500 x 1500: the elevation, the coefficients, the
# derivatives' coefficients and CasADi's copies of them).
GRID_BYTES_PER_POINT = 200
CSV_COLUMNS = 3  # x, y, z


class GridError(ValueError):
    """A bathymetry file that cannot be used; the message names the file and the point."""


@dataclass(frozen=True, eq=False)
class BathymetryGrid:
    """The seabed's elevation on a rectilinear grid.

    Attributes
    ----------
    file : str
        Absolute path of the file it was read from.
    x : array (nx,), m
        Strictly increasing.
    y : array (ny,), m
        Strictly increasing.
    elevation : array (nx, ny), m
        ``z(x_i, y_j)``, up, the sea surface at 0; finite.
    """

    file: str
    x: np.ndarray
    y: np.ndarray
    elevation: np.ndarray

    def contains(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Whether each point ``(x, y)`` (m) lies on the grid, its edges included."""
        return (self.x[0] <= x) & (x <= self.x[-1]) & (self.y[0] <= y) & (y <= self.y[-1])

    def extent(self) -> str:
        """The grid's span in words, for messages: ``x in [a, b] m, y in [c, d] m``."""
        return f"x in [{self.x[0]:g}, {self.x[-1]:g}] m, y in [{self.y[0]:g}, {self.y[-1]:g}] m"


def available_memory() -> int:
    """Memory (bytes) the machine can give a new allocation now: Linux's ``MemAvailable``.

    Elsewhere, or where ``/proc/meminfo`` cannot be read, the physical memory.
    """
    try:
        with open("/proc/meminfo") as info:
            for line in info:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")


def check_grid_size(path: str, points: int, shape: str) -> None:
    """Refuse a grid whose spline cannot fit in memory, before its data are read.

    Parameters
    ----------
    path : str
    points : int
        Grid points (or CSV rows).
    shape : str
        The grid's size in words, for the message (``"300 x 200"``).

    Raises
    ------
    GridError
        ``points`` at :data:`GRID_BYTES_PER_POINT` are more than :func:`available_memory`.
    """
    need, have = points * GRID_BYTES_PER_POINT, available_memory()
    if need > have:
        raise GridError(
            f"{path}: a grid of {shape} points needs about {need / 1e9:.3g} GB for its "
            f"spline ({GRID_BYTES_PER_POINT} bytes a point), more than the "
            f"{have / 1e9:.3g} GB available; crop it to the area the tow covers or coarsen it"
        )


def read_grid(path: str | os.PathLike, variable: str = "elevation") -> BathymetryGrid:
    """Read and check a bathymetry file (netCDF or CSV, by its suffix).

    Parameters
    ----------
    path : path-like
        The ``.nc`` or ``.csv`` file.
    variable : str
        The elevation's variable in a netCDF file (a CSV's third column is the elevation).

    Returns
    -------
    BathymetryGrid

    Raises
    ------
    GridError
        Unreadable file, unknown suffix, missing variable or coordinate, non-metric units, an axis
        that is not strictly monotone or too short, a NaN or infinite elevation, a CSV that misses
        or repeats a grid point; the message names the file and the point.
    """
    try:
        path = Path(path).resolve()
        stat = path.stat()
    except RuntimeError:  # Python < 3.13: a loop of symbolic links
        raise GridError(f"{path}: cannot read (a loop of symbolic links)") from None
    except OSError as error:
        raise GridError(f"{path}: cannot read ({error.strerror})") from None
    return _read_cached(str(path), variable, stat.st_size, stat.st_mtime_ns)


@functools.lru_cache(maxsize=16)
def _read_cached(path: str, variable: str, size: int, mtime: int) -> BathymetryGrid:
    suffix = Path(path).suffix.lower()
    if suffix == ".nc":
        x, y, z = _read_netcdf(path, variable)
    elif suffix == ".csv":
        x, y, z = _read_csv(path)
    else:
        raise GridError(f"{path}: unknown bathymetry format {suffix!r}; expected .nc or .csv")
    for name, axis in (("x", x), ("y", y)):
        if axis.size < MIN_AXIS_POINTS:
            raise GridError(
                f"{path}: axis {name} has {axis.size} points; a cubic B-spline needs at least "
                f"{MIN_AXIS_POINTS}"
            )
    bad = ~np.isfinite(z)
    if bad.any():
        i, j = np.argwhere(bad)[0]
        raise GridError(
            f"{path}: elevation is {z[i, j]} at (x, y) = ({x[i]:g}, {y[j]:g}) m "
            f"({int(bad.sum())} non-finite points); fill or crop them"
        )
    for array in (x, y, z):
        array.setflags(write=False)
    return BathymetryGrid(path, x, y, z)


def _monotone_axis(path: str, name: str, values: np.ndarray) -> tuple[np.ndarray, bool]:
    """The axis strictly increasing, and whether it had to be flipped."""
    values = np.asarray(values, dtype=float)
    if values.ndim != 1:
        raise GridError(f"{path}: coordinate {name} must be 1-D, got shape {values.shape}")
    if not np.all(np.isfinite(values)):
        k = int(np.argmax(~np.isfinite(values)))
        raise GridError(f"{path}: coordinate {name}[{k}] = {values[k]} is not finite")
    steps = np.diff(values)
    if np.all(steps > 0):
        return values, False
    if np.all(steps < 0):
        return values[::-1].copy(), True
    k = int(np.argmax(steps <= 0) if steps[0] > 0 else np.argmax(steps >= 0))
    raise GridError(
        f"{path}: coordinate {name} is not strictly monotone at index {k + 1} "
        f"({name} = {values[k]:g} then {values[k + 1]:g} m)"
    )


def _check_units(path: str, name: str, attributes) -> None:
    units = attributes.get("units")
    if units is not None and str(units).strip().lower() not in METRES:
        raise GridError(f"{path}: {name} has units {units!r}; expected metres ('m')")


def _read_netcdf(path: str, variable: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    import xarray as xr

    try:
        with xr.open_dataset(path) as data:
            field = _netcdf_field(path, data, variable)  # its size checked before it is read
            field.load()
    except GridError:
        raise
    except Exception as error:  # noqa: BLE001 - every reader failure is the file's problem
        detail = f"{type(error).__name__}: {(str(error).splitlines() or [''])[0]}"
        raise GridError(f"{path}: cannot read as netCDF ({detail})") from None
    _check_units(path, variable, field.attrs)
    axes = []
    for name in ("x", "y"):
        if name not in field.coords:
            raise GridError(f"{path}: dimension {name} has no coordinate values")
        _check_units(path, name, field.coords[name].attrs)
        axis, flipped = _monotone_axis(path, name, field.coords[name].values)
        if flipped:
            field = field.isel({name: slice(None, None, -1)})
        axes.append(axis)
    z = np.array(field.transpose("x", "y").values, dtype=float)
    return axes[0], axes[1], z


def _netcdf_field(path: str, data, variable: str):
    """The elevation variable of an open dataset, its dimensions and size checked (not read)."""
    if variable not in data.data_vars:
        found = ", ".join(map(str, data.data_vars)) or "none"
        raise GridError(f"{path}: no variable {variable!r} (variables: {found})")
    field = data[variable]
    if set(field.dims) != {"x", "y"}:
        raise GridError(
            f"{path}: variable {variable!r} has dimensions {field.dims}; expected ('x', 'y')"
        )
    nx, ny = field.sizes["x"], field.sizes["y"]
    check_grid_size(path, nx * ny, f"{nx} x {ny}")
    return field


def _read_csv(path: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    data = _csv_rows(path)
    bad = ~np.isfinite(data).all(axis=1)
    if bad.any():
        row = int(np.argmax(bad))
        x, y, z = data[row]
        raise GridError(
            f"{path}: row {row + 1} of the data, (x, y, z) = ({x:g}, {y:g}, {z:g}) m, is not finite"
        )
    x, ix = np.unique(data[:, 0], return_inverse=True)
    y, iy = np.unique(data[:, 1], return_inverse=True)
    codes = np.sort(ix * y.size + iy)  # one code per grid point, without a (nx, ny) count array
    twice = np.flatnonzero(np.diff(codes) == 0)
    if twice.size:
        i, j = divmod(int(codes[twice[0]]), y.size)
        raise GridError(f"{path}: grid point (x, y) = ({x[i]:g}, {y[j]:g}) m is given twice")
    if codes.size < x.size * y.size:
        gaps = np.flatnonzero(codes != np.arange(codes.size))
        i, j = divmod(int(gaps[0]) if gaps.size else codes.size, y.size)
        raise GridError(
            f"{path}: not a regular grid: point (x, y) = ({x[i]:g}, {y[j]:g}) m is missing "
            f"({x.size * y.size - codes.size} of {x.size} x {y.size} missing)"
        )
    z = np.empty((x.size, y.size))
    z[ix, iy] = data[:, 2]
    return x, y, z


def _csv_rows(path: str) -> np.ndarray:
    """The data rows (k, 3) of a CSV grid: comments (``#``) and a header line left out.

    The text may start with a UTF-8 byte-order mark (an Excel export).
    """
    try:
        with open(path, encoding="utf-8-sig") as handle:
            text = handle.read()
    except OSError as error:
        raise GridError(f"{path}: cannot read ({error.strerror})") from None
    except UnicodeDecodeError as error:
        raise GridError(
            f"{path}: not a UTF-8 text file (byte {error.start}); expected CSV rows x, y, z"
        ) from None
    numbered = [(k, line.split("#", 1)[0].strip()) for k, line in enumerate(text.splitlines(), 1)]
    numbered = [(k, line) for k, line in numbered if line]
    header = bool(numbered) and _csv_fields(numbered[0][1]) is None
    if header:
        numbered = numbered[1:]
    if not numbered:
        what = "only a header line" if header else "an empty file"
        raise GridError(f"{path}: no data rows ({what}); expected rows x, y, z (m)")
    check_grid_size(path, len(numbered), f"{len(numbered)} rows, as many")
    try:
        rows = np.loadtxt([line for _, line in numbered], delimiter=",", ndmin=2)
    except ValueError:
        rows = None
    if rows is not None and rows.shape[1] == CSV_COLUMNS:
        return rows
    for number, line in numbered:  # name the first line numpy could not read
        fields = line.split(",")
        if len(fields) != CSV_COLUMNS:
            trailing = " (a trailing comma?)" if fields[-1].strip() == "" else ""
            raise GridError(
                f"{path}: line {number} has {len(fields)} fields{trailing}; expected "
                f"{CSV_COLUMNS}: x, y, z (m)"
            )
        if _csv_fields(line) is None:
            raise GridError(f"{path}: line {number} = {line[:40]!r} is not three numbers x, y, z")
    raise GridError(f"{path}: cannot read as CSV of rows x, y, z (m)")


def _csv_fields(line: str) -> list[float] | None:
    """The numbers of one CSV line, or None if a field is not a number."""
    try:
        return [float(field) for field in line.split(",")]
    except ValueError:
        return None
