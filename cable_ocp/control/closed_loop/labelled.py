"""An ``MpcResult`` as a labelled ``xarray.Dataset``, and the reader of its format-1 files.

Every field is a variable or an attribute by its type (:mod:`cable_ocp.scene.labelled`): the
plant's series over ``time`` (positions over ``time`` and ``component``), the solves over
``sample``, the reference runs over ``reference`` (and ``time``), the winch range over ``bound``;
statuses, failures and settings are attributes (JSON).
"""

from __future__ import annotations

import json
import zipfile
import zlib
from pathlib import Path

import numpy as np
import xarray as xr

from cable_ocp.scene import labelled
from cable_ocp.scene.records import check_run

KIND = "MpcResult"
FILE = "mpc.nc"
SERIES = ("time", "winch_angle", "planned_angle", "clearance_error")
DIMS = {
    **{name: ("time",) for name in SERIES},
    "end": ("time", "component"),
    "top": ("time", "component"),
    **{name: ("sample",) for name in ("sample_times", "solve_times", "iterations")},
    "angle_range": ("bound",),
    "references": ("reference", "time"),
    "reference_omegas": ("reference",),
}
COORDS = {"component": labelled.COMPONENT, "bound": ("min", "max")}
UNITS = {"references": "m", "reference_omegas": "m"}  # the docstring gives them in the text
# Format 1 (cable_ocp 0.1): mpc.json held the summary under these names, mpc.npz the arrays.
LEGACY_NAMES = {
    "omega_m": "omega", "real_time_factor": "real_time_factor",
    "worst_solve_time_s": "worst_solve_time", "wall_time_s": "wall_time",
    "build_time_s": "build_time", "limited_steps": "limited_steps", "success": "success",
    "failures": "failures", "statuses": "statuses", "settings": "settings", "status": "status",
    "reference_omegas_m": "reference_omegas",
}  # fmt: skip


def to_xarray(result) -> xr.Dataset:
    """The closed-loop run as a Dataset (see the module docstring)."""
    return labelled.to_dataset(result, KIND, DIMS, COORDS, UNITS)


def load(cls, folder: Path):
    """Read ``folder/mpc.nc``, or the format-1 files ``mpc.json`` and ``mpc.npz``.

    Raises
    ------
    ValueError
        Naming the file, if it is missing, truncated, garbled or of a newer format.
    """
    folder = Path(folder)
    netcdf = folder / FILE
    if not netcdf.exists() and (folder / "mpc.json").exists():
        return _load_format_1(cls, folder)
    dataset = labelled.read(netcdf, KIND)
    try:
        values = labelled.from_dataset(cls, dataset)
        for name in (*SERIES, "end", "top"):
            if np.shape(values[name])[:1] != np.shape(values["time"]):
                raise ValueError(
                    f"{name} of shape {np.shape(values[name])} does not fit time "
                    f"{np.shape(values['time'])}"
                )
        check_run(values["time"], {"end": values["end"], "top": values["top"]})
        return cls(**values)
    except (ValueError, KeyError, TypeError) as error:
        raise ValueError(
            f"{netcdf}: not a readable closed-loop result ({type(error).__name__}: {error})"
        ) from None


def _load_format_1(cls, folder: Path):
    path = folder / "mpc.json"
    try:
        meta = json.loads(path.read_text())
        values = {field: meta[name] for name, field in LEGACY_NAMES.items() if name in meta}
        values["angle_range"] = tuple(float(v) for v in meta["angle_range_rad"])
        path = folder / "mpc.npz"
        with np.load(path) as data:
            arrays = {name: np.asarray(data[name]) for name in data.files}
        references = {k.removeprefix("reference "): v for k, v in arrays.items()
                      if k.startswith("reference ")}  # fmt: skip
        arrays = {k: v for k, v in arrays.items() if not k.startswith("reference ")}
        return cls(**values, **arrays, references=references)
    except (OSError, ValueError, KeyError, TypeError, RecursionError, EOFError,
            zipfile.BadZipFile, zlib.error) as error:  # fmt: skip
        raise ValueError(
            f"{path}: not a readable closed-loop result of format 1 (mpc.json + mpc.npz, "
            f"cable_ocp 0.1) ({type(error).__name__}: {error})"
        ) from None
