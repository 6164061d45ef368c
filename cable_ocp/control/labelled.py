"""An ``OcpResult`` as a labelled ``xarray.Dataset``: its fields, and its verified trajectory.

Every field of the result is a variable or an attribute (by its type,
:mod:`cable_ocp.scene.labelled`): ``parameters`` over ``parameter``, ``history`` over
``iteration`` (an evaluation for Nelder-Mead), ``refinements`` over ``solve``, the numbers as
0-d variables, the strings (``method``, ``control``, ``status``, ``notes``) as attributes. The
verified trajectory's variables (:mod:`cable_ocp.simulation.labelled`) join them over ``time``;
where a name is the result's too (``omega``), the trajectory's is prefixed ``trajectory_``. A
result without a trajectory has no ``time`` dimension.
"""

from __future__ import annotations

import xarray as xr

from cable_ocp.scene import labelled
from cable_ocp.simulation import labelled as run_labelled

KIND = "OcpResult"
FILE = "result.nc"
PREFIX = "trajectory_"
DIMS = {"parameters": ("parameter",), "history": ("iteration",), "refinements": ("solve",)}
# What the docstring cannot state: units that depend on the method or the control.
HISTORY_UNITS = {"ipopt": "m2", "nelder-mead": "m"}
PARAMETER_UNITS = {"spline": "rad", "hermite": "rad, then rad s-1 (angles, then rates)"}


def to_xarray(result) -> xr.Dataset:
    """The result as a Dataset (see the module docstring)."""
    units = {
        "history": HISTORY_UNITS.get(result.method, labelled.DIMENSIONLESS),
        "refinements": "m",
        "parameters": PARAMETER_UNITS.get(result.control.partition("(")[0], "rad"),
    }
    dataset = labelled.to_dataset(result, KIND, DIMS, units=units, skip=("trajectory",))
    if result.trajectory is None:
        return dataset
    run = result.trajectory.to_xarray()
    run = run.rename({n: PREFIX + n for n in run.data_vars if n in dataset.variables})
    merged = xr.merge([dataset, run], combine_attrs="override", join="exact")
    for name, value in run.attrs.items():
        if name not in dataset.attrs:
            merged.attrs[name] = value
    return merged


def from_dataset(cls, dataset: xr.Dataset, trajectory_class) -> dict:
    """The fields of an ``OcpResult`` (class ``cls``) from its Dataset.

    Raises
    ------
    ValueError, KeyError, TypeError
        A field is missing or does not fit.
    """
    values = labelled.from_dataset(cls, dataset, skip=("trajectory",))
    values["trajectory"] = None
    if "time" in dataset.dims:
        names = [n for n in dataset.data_vars if "time" in dataset[n].dims or n.startswith(PREFIX)]
        run = dataset[names].rename({n: n[len(PREFIX) :] for n in names if n.startswith(PREFIX)})
        run.attrs = dict(dataset.attrs)
        try:
            run_values = run_labelled.from_dataset(run, trajectory_class)
            values["trajectory"] = trajectory_class(**run_values)
        except ValueError as error:
            raise ValueError(f"trajectory: {error}") from None
    return values
