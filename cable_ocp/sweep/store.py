"""A sweep's folder: one netCDF file per finished case, written at once, and the assembled Dataset.

Layout of ``DIR``::

    DIR/.cable_ocp-results    the marker of a results folder (cable_ocp.scene.output.MARKER)
    .DIR.cable_ocp-lock       beside DIR: held by the run writing DIR, names its owner
    DIR/sweep.json            the manifest: sweep file, and each case's overrides and fingerprint
    DIR/sweep.toml            a copy of the sweep file
    DIR/cases/case_00007.nc   case 7, written atomically (temporary file + rename) as it finishes
    DIR/sweep.nc              all cases in one xarray Dataset (assembled from the case files)

A folder is a sweep folder only with the marker: a folder of the user's, even one holding a
``sweep.json``, is refused and left untouched. Every file is written by the process that runs
the sweep, without Dask's help, so a lost scheduler cannot lose a finished case; files get the
folder's permissions (without execute bits). Scratch files (``.NAME.XXXXXXXX.tmp``) that a killed
run left behind are removed by the next run.

The Dataset has dimensions ``case`` and ``time``. Each swept key is a coordinate along ``case``
named by its dotted key (``"top.tow.surge_speed"``); a vector is one coordinate per component,
``"environment.current[0]"`` .. ``[2]``. Select with a boolean mask, e.g.
``ds.where(ds["top.tow.surge_speed"] == 0.8, drop=True)``, or open with ``open_sweep(path,
index=True)`` to make ``case`` a multi-index of the swept coordinates and use
``ds.sel({"top.tow.surge_speed": 0.8})``. Cases of different durations share the union of the
output times, padded with NaN.
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from cable_ocp import result_files
from cable_ocp.result_files import SWEEP_FILE, netcdf
from cable_ocp.scene.output import MARKER, FolderInUse, check_target, file_mode, write_atomic
from cable_ocp.scene.output import folder_lock as output_lock
from cable_ocp.sweep.execute import SERIES
from cable_ocp.sweep.spec import Case, SweepSpec

SCALARS = ("omega", "wall_time")
OPTIMIZE_SCALARS = ("omega_model", "iterations", "evaluations")
TEXT = ("status", "reason")
LOCK = ".sweep.lock"  # the lock inside the folder of cable_ocp up to 0.3: removed when free
# What a sweep writes in its folder: a folder holding anything else is not a sweep's.
SWEEP_NAMES = {MARKER, LOCK, "sweep.json", "sweep.toml", "cases", SWEEP_FILE}
RECOVER = "rerun the same command with --retry-failed to compute it again"
TIME_DECIMALS = 9  # output times rounded to 1 ns so equal times of different cases coincide
# The units of every variable of numbers that a case file and sweep.nc hold (CF spelling; the
# writer refuses one without): the run's series, its figures and the optimiser's counts.
UNITS = {
    "omega": "m", "wall_time": "s", "omega_model": "m", "iterations": "1", "evaluations": "1",
    "winch_angle": "rad", "end_x": "m", "end_y": "m", "end_z": "m", "clearance_error": "m",
    "top_tension": "N", "time": "s",
}  # fmt: skip


def case_path(folder: Path, index: int) -> Path:
    """The file of case ``index`` in a sweep folder."""
    return Path(folder) / "cases" / f"case_{index:05d}.nc"


def _write(dataset: xr.Dataset, target: Path) -> None:
    """Write ``dataset`` to ``target`` by the one netCDF writer (atomic, without Dask).

    The file gets its folder's permissions (:func:`file_mode`).
    """
    target.parent.mkdir(parents=True, exist_ok=True)  # (its mode is read before the write)
    netcdf.write(dataset, target, mode=file_mode(target.parent))


def _with_units(dataset: xr.Dataset) -> xr.Dataset:
    """``dataset`` with the :data:`UNITS` of its variables; returns it."""
    for name, unit in UNITS.items():
        if name in dataset.variables:
            dataset[name].attrs["units"] = unit
    return dataset


def write_case(folder: Path, case: Case, record: dict[str, Any]) -> Path:
    """Save one case's record (from :func:`~cable_ocp.sweep.execute.run_case`) atomically."""
    data: dict[str, Any] = {}
    if "time" in record:
        time_ = np.round(record["time"], TIME_DECIMALS)
        data.update({name: ("time", record[name]) for name in SERIES})
        coords = {"time": time_}
    else:
        coords = {}
    for name in (*SCALARS, *OPTIMIZE_SCALARS, "solver_status", *TEXT, "success"):
        if name in record:
            data[name] = ((), record[name])
    attrs = {
        "index": case.index,
        "fingerprint": case.fingerprint,
        "overrides": json.dumps(case.overrides),
    }
    path = case_path(folder, case.index)
    _write(_with_units(xr.Dataset(data, coords=coords, attrs=attrs)), path)
    return path


def read_case(path: Path) -> xr.Dataset:
    """A case file, loaded into memory (the file is closed).

    Raises
    ------
    ValueError
        Naming the file, if it is empty, truncated or not a case file, and how to recover.
    """
    try:
        with xr.open_dataset(path) as dataset:
            dataset = dataset.load()
        if "status" not in dataset or "fingerprint" not in dataset.attrs:
            raise ValueError("no status or fingerprint")
    except (OSError, ValueError, KeyError, TypeError, RuntimeError) as error:
        detail = "empty file" if _size(path) == 0 else " ".join(str(error).split())[:120]
        raise ValueError(f"{path}: damaged case file ({detail}): {RECOVER}") from None
    return dataset


def _size(path: Path) -> int:
    try:
        return path.stat().st_size
    except OSError:
        return -1


def _manifest(spec: SweepSpec) -> dict[str, Any]:
    return {
        "sweep_file": str(spec.path),
        "scene": str(spec.scene_path),
        "task": spec.task,
        "cases": [{"overrides": c.overrides, "fingerprint": c.fingerprint} for c in spec.cases],
    }


def read_manifest(path: Path) -> dict[str, Any]:
    """A sweep folder's ``sweep.json``, checked.

    Raises
    ------
    ValueError
        Naming the file and how to recover, if it is unreadable or not a manifest.
    """
    try:
        held = json.loads(path.read_text(encoding="utf-8"))
        cases = held["cases"] if isinstance(held, dict) else None
        if not isinstance(cases, list):
            raise ValueError("no list of cases")
        for case in cases:
            if not (isinstance(case, dict) and isinstance(case.get("overrides"), dict)
                    and isinstance(case.get("fingerprint"), str)):  # fmt: skip
                raise ValueError("a case without overrides or fingerprint")
    except (OSError, ValueError, RecursionError) as error:
        detail = " ".join(str(error).split())[:120] or type(error).__name__
        raise ValueError(
            f"{path}: damaged sweep manifest ({detail}): delete it and rerun the same command "
            "(the case files are kept, each checked against this sweep)"
        ) from None
    return held


def check_folder(folder: Path, spec: SweepSpec) -> None:
    """Refuse a ``--out`` that is not a new, empty or this sweep's folder; write nothing.

    Raises
    ------
    ValueError
        Naming the folder and why: a user's folder (no marker, with or without a
        ``sweep.json``), another command's results, another sweep's, a damaged manifest, an
        unwritable folder; see also :func:`~cable_ocp.scene.output.check_target`.
    """
    folder = Path(folder)
    names = {p.name for p in folder.iterdir()} if folder.is_dir() else set()
    if folder.is_dir() and not os.access(folder, os.W_OK | os.X_OK):  # a read-only mount too
        raise ValueError(f"--out {folder}: the folder is not writable; nothing was written")
    if names - {LOCK} and MARKER not in names:
        older = (
            f" (if an older cable-ocp wrote it, add an empty file {folder / MARKER} to resume it)"
            if {"sweep.json", "cases"} <= names
            else ""
        )
        raise ValueError(
            f"--out {folder} is not empty and holds no sweep of cable-ocp (no {MARKER} "
            f"marker){older}: give a new or empty folder; nothing was written"
        )
    if names - {LOCK} or not names:  # (a lock alone: a sweep that is claiming it)
        check_target(folder)
    if not names - {LOCK, MARKER}:
        return
    if "sweep.json" not in names:
        if names - SWEEP_NAMES:
            raise ValueError(
                f"--out {folder} holds the results of another cable-ocp command, not a sweep: "
                "give a new or empty folder"
            )
        return  # a sweep folder whose manifest was deleted to recover: rebuilt
    held = read_manifest(folder / "sweep.json")
    mine, theirs = _manifest(spec)["cases"], held["cases"]
    advice = f"choose another --out or delete {folder} to start over"
    if len(mine) != len(theirs):
        raise ValueError(
            f"--out {folder} belongs to another sweep ({held.get('sweep_file')}, "
            f"{len(theirs)} cases; this one has {len(mine)}): {advice}"
        )
    for index, (a, b) in enumerate(zip(mine, theirs, strict=True)):
        if a["overrides"] != b["overrides"]:
            raise ValueError(
                f"--out {folder} belongs to another sweep ({held.get('sweep_file')}): its "
                f"case {index} is {json.dumps(b['overrides'])}, this sweep's is "
                f"{json.dumps(a['overrides'])}: {advice}"
            )
        if a["fingerprint"] != b["fingerprint"]:
            raise ValueError(
                f"--out {folder} was made by this sweep with another scene file content, "
                f"[set] or optimiser settings (case {index} differs): {advice}"
            )


def mark_folder(folder: Path) -> None:
    """Create ``folder`` (if new) with the marker of a results folder (if it has none)."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    if not (folder / MARKER).is_file():
        write_atomic(folder / MARKER, "A cable-ocp sweep folder: rerun its sweep to resume.\n")


def claim_folder(folder: Path, spec: SweepSpec) -> None:
    """Make ``folder`` this sweep's (marker, manifest, copy of the sweep file), or refuse it.

    Every file is replaced atomically, so a reader never sees a part of one. Call it holding
    :func:`folder_lock`, as :func:`~cable_ocp.sweep.runner.run_sweep` does.

    Raises
    ------
    ValueError
        As :func:`check_folder`.
    """
    folder = Path(folder)
    check_folder(folder, spec)
    mark_folder(folder)
    cases = folder / "cases"
    if not cases.is_dir():
        cases.mkdir()
        os.chmod(cases, os.stat(folder).st_mode & 0o777)  # the folder's, as its files
    write_atomic(folder / "sweep.json", json.dumps(_manifest(spec), indent=1))
    write_atomic(folder / "sweep.toml", spec.text)


def remove_scratch(folder: Path) -> list[Path]:
    """Remove the scratch files a killed run left in a sweep folder; return them."""
    folder = Path(folder)
    stale = [*folder.glob(".*.tmp"), *(folder / "cases").glob(".case_*")]
    for path in stale:
        if path.is_file() and not path.is_symlink():
            path.unlink(missing_ok=True)
    return stale


@contextmanager
def folder_lock(folder: Path, what: str = "") -> Iterator[None]:
    """Hold the sweep folder's lock for the block; refuse a folder another process holds.

    The one lock of a results folder (:func:`cable_ocp.scene.output.folder_lock`), so a sweep
    and any other command never write one folder at the same time.

    Raises
    ------
    ValueError
        Naming the folder and the owner, if another process holds the lock.
    """
    try:
        with output_lock(folder, what or None, reentrant=False):
            _remove_old_lock(Path(folder))
            yield
    except FolderInUse as error:
        raise ValueError(
            f"--out {folder} is in use by another {'sweep' if ' sweep ' in error.holder else 'run'}"
            f" ({error.holder}): wait for it to end, or give another --out"
        ) from None


def _remove_old_lock(folder: Path) -> None:
    """Remove the ``.sweep.lock`` that cable_ocp up to 0.3 left in a sweep folder.

    Those versions held it by ``flock`` while they ran; a lock that a live sweep of theirs holds
    is left to it, a free one (its sweep finished) is removed.
    """
    try:
        import fcntl
    except ModuleNotFoundError:  # Windows: those versions took no lock there either
        return
    path = folder / LOCK
    try:
        handle = os.open(path, os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0))
    except OSError:  # none (the usual case), or not ours to open
        return
    try:
        fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:  # held by a running sweep of an older cable_ocp
        return
    else:
        path.unlink(missing_ok=True)
    finally:
        os.close(handle)


def case_statuses(folder: Path, spec: SweepSpec) -> dict[int, str]:
    """Status of each case whose file is present: ``"ok"``, ``"failed"`` or ``"damaged"``.

    Raises
    ------
    ValueError
        A case file whose fingerprint is not its case's (a foreign or stale file).
    """
    statuses = {}
    for case in spec.cases:
        path = case_path(folder, case.index)
        if not path.is_file():
            continue
        try:
            dataset = read_case(path)
        except ValueError:
            statuses[case.index] = "damaged"
            continue
        stored = dataset.attrs.get("fingerprint")
        if stored != case.fingerprint:
            raise ValueError(
                f"{path} was made by another sweep (fingerprint {stored}, expected "
                f"{case.fingerprint}): delete it or choose another --out"
            )
        statuses[case.index] = "ok" if str(dataset["status"].values) == "ok" else "failed"
    return statuses


def _coordinates(spec: SweepSpec) -> dict[str, tuple[str, np.ndarray]]:
    """The swept values as coordinates along ``case`` (vectors split into components)."""
    coords = {}
    for key in spec.swept:
        values = [c.overrides[key] for c in spec.cases]
        if all(isinstance(v, list | tuple) for v in values):
            for k in range(len(values[0])):
                coords[f"{key}[{k}]"] = ("case", np.array([float(v[k]) for v in values]))
        elif all(isinstance(v, str) for v in values):
            coords[key] = ("case", np.array(values, dtype=object))
        else:
            coords[key] = ("case", np.array(values))
    return coords


def assemble(folder: Path, spec: SweepSpec) -> xr.Dataset:
    """All cases in one Dataset; a case without a file has status ``"not run"``."""
    count = len(spec.cases)
    cases = {}
    for case in spec.cases:
        path = case_path(folder, case.index)
        if path.is_file():
            cases[case.index] = read_case(path)
    times = sorted({float(t) for d in cases.values() if "time" in d.coords for t in d.time.values})
    time = np.array(times, dtype=float)
    position = {t: k for k, t in enumerate(times)}
    scalars = (*SCALARS, *OPTIMIZE_SCALARS) if spec.task == "optimize" else SCALARS
    texts = (*TEXT, "solver_status") if spec.task == "optimize" else TEXT
    data: dict[str, Any] = {name: np.full((count, time.size), np.nan) for name in SERIES}
    data.update({name: np.full(count, np.nan) for name in scalars})
    data.update({name: np.array(["" for _ in range(count)], dtype=object) for name in texts})
    data["status"][:] = "not run"
    data["success"] = np.zeros(count, dtype=bool)
    for index, dataset in cases.items():
        if "time" in dataset.coords:
            columns = [position[float(t)] for t in dataset.time.values]
            for name in SERIES:
                data[name][index, columns] = dataset[name].values
        for name in (*scalars, *texts, "success"):
            if name in dataset:
                data[name][index] = dataset[name].values.item()
    variables = {
        name: (("case", "time") if name in SERIES else ("case",), values)
        for name, values in data.items()
    }
    coords = {"case": np.arange(count), "time": time, **_coordinates(spec)}
    settings = asdict(spec.settings) if spec.settings is not None else None
    attrs = {
        **netcdf.file_attributes(result_files.SWEEP_KIND),
        "sweep_file": str(spec.path),
        "sweep_text": spec.text,
        "scene": str(spec.scene_path),
        "task": spec.task,
        "method": spec.method if spec.task == "optimize" else "",
        "settings": json.dumps(settings, default=str),
        "design": spec.design,
        "swept": json.dumps(list(spec.swept)),
        "fixed": json.dumps(spec.fixed),
    }
    return _with_units(xr.Dataset(variables, coords=coords, attrs=attrs))


def save_dataset(folder: Path, dataset: xr.Dataset) -> Path:
    """Write the assembled Dataset to ``folder/sweep.nc`` atomically."""
    path = Path(folder) / SWEEP_FILE
    _write(dataset, path)
    return path


def open_sweep(path: str | Path, index: bool = False) -> xr.Dataset:
    """Read ``sweep.nc`` (or the folder that holds it) into memory.

    Parameters
    ----------
    path : path-like
        The file or the sweep folder.
    index : bool
        Make ``case`` a multi-index of the swept coordinates, so that
        ``ds.sel({"top.tow.surge_speed": 0.8})`` works.
    """
    path = Path(path)
    dataset = result_files.read_sweep(path / SWEEP_FILE if path.is_dir() else path)
    if index:
        swept = [n for n in dataset.coords if n not in ("case", "time")]
        if swept:
            dataset = dataset.drop_vars("case").set_index(case=swept)
    return dataset
