"""A sweep's folder: one netCDF file per finished case, written at once, and the assembled Dataset.

Layout of ``DIR``::

    DIR/sweep.json            the manifest: sweep file, and each case's overrides and fingerprint
    DIR/sweep.toml            a copy of the sweep file
    DIR/cases/case_00007.nc   case 7, written atomically (temporary file + rename) as it finishes
    DIR/sweep.nc              all cases in one xarray Dataset (assembled from the case files)

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
import tempfile
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from cable_ocp.sweep.execute import SERIES
from cable_ocp.sweep.spec import Case, SweepSpec

SCALARS = ("omega", "wall_time")
OPTIMIZE_SCALARS = ("omega_model", "iterations", "evaluations")
TEXT = ("status", "reason")
TIME_DECIMALS = 9  # output times rounded to 1 ns so equal times of different cases coincide
UNITS = {
    "omega": "m", "wall_time": "s", "omega_model": "m", "winch_angle": "rad", "end_x": "m",
    "end_y": "m", "end_z": "m", "clearance_error": "m", "top_tension": "N", "time": "s",
}  # fmt: skip


def case_path(folder: Path, index: int) -> Path:
    """The file of case ``index`` in a sweep folder."""
    return Path(folder) / "cases" / f"case_{index:05d}.nc"


def _atomic_netcdf(dataset: xr.Dataset, target: Path) -> None:
    target.parent.mkdir(parents=True, exist_ok=True)
    handle, scratch = tempfile.mkstemp(prefix=f".{target.name}.", dir=target.parent)
    os.close(handle)
    try:
        dataset.to_netcdf(scratch)
        os.replace(scratch, target)
    except BaseException:
        Path(scratch).unlink(missing_ok=True)
        raise


def write_case(folder: Path, case: Case, record: dict[str, Any]) -> Path:
    """Save one case's record (from :func:`~cable_ocp.sweep.execute.run_case`) atomically."""
    data: dict[str, Any] = {}
    if "time" in record:
        time = np.round(record["time"], TIME_DECIMALS)
        data.update({name: ("time", record[name]) for name in SERIES})
        coords = {"time": time}
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
    _atomic_netcdf(xr.Dataset(data, coords=coords, attrs=attrs), path)
    return path


def read_case(path: Path) -> xr.Dataset:
    """A case file, loaded into memory (the file is closed)."""
    with xr.open_dataset(path) as dataset:
        return dataset.load()


def _manifest(spec: SweepSpec) -> dict[str, Any]:
    return {
        "sweep_file": str(spec.path),
        "scene": str(spec.scene_path),
        "task": spec.task,
        "cases": [{"overrides": c.overrides, "fingerprint": c.fingerprint} for c in spec.cases],
    }


def claim_folder(folder: Path, spec: SweepSpec) -> None:
    """Make ``folder`` this sweep's, or refuse one that holds anything else.

    Raises
    ------
    ValueError
        ``folder`` is not empty and not a sweep folder, or belongs to another sweep (other cases,
        or the same overrides on a changed scene file or other optimiser settings).
    """
    folder = Path(folder)
    manifest_path = folder / "sweep.json"
    wanted = _manifest(spec)
    if manifest_path.is_file():
        held = json.loads(manifest_path.read_text())
        mine, theirs = wanted["cases"], held.get("cases", [])
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
    elif folder.exists() and any(folder.iterdir()):
        raise ValueError(f"--out {folder} is not empty and holds no sweep (no sweep.json)")
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "cases").mkdir(exist_ok=True)
    manifest_path.write_text(json.dumps(wanted, indent=1))
    (folder / "sweep.toml").write_text(spec.text)


def finished_cases(folder: Path, spec: SweepSpec) -> set[int]:
    """Indices of the cases whose file is present (ok or failed) and made by this sweep.

    Raises
    ------
    ValueError
        A case file whose fingerprint is not its case's (a foreign or stale file).
    """
    done = set()
    for case in spec.cases:
        path = case_path(folder, case.index)
        if not path.is_file():
            continue
        with xr.open_dataset(path) as dataset:
            stored = dataset.attrs.get("fingerprint")
        if stored != case.fingerprint:
            raise ValueError(
                f"{path} was made by another sweep (fingerprint {stored}, expected "
                f"{case.fingerprint}): delete it or choose another --out"
            )
        done.add(case.index)
    return done


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
    dataset = xr.Dataset(variables, coords=coords, attrs=attrs)
    for name, unit in UNITS.items():
        if name in dataset.variables:
            dataset[name].attrs["units"] = unit
    return dataset


def save_dataset(folder: Path, dataset: xr.Dataset) -> Path:
    """Write the assembled Dataset to ``folder/sweep.nc`` atomically."""
    path = Path(folder) / "sweep.nc"
    _atomic_netcdf(dataset, path)
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
    if path.is_dir():
        path = path / "sweep.nc"
    with xr.open_dataset(path) as dataset:
        dataset = dataset.load()
    if index:
        swept = [n for n in dataset.coords if n not in ("case", "time")]
        if swept:
            dataset = dataset.drop_vars("case").set_index(case=swept)
    return dataset
