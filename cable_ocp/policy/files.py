"""A policy's netCDF form: its network, family, training data and figures, checked on reading.

:func:`to_dataset` lays a policy out as an ``xarray.Dataset`` (every variable with its CF unit:
each feature's observations and normalisation in that feature's unit, the weights in the
normalised network's, 1); :func:`fields_of` reads the fields back and refuses a file whose
numbers do not hash to the digest it was written with (a damaged file), a network whose layers
do not fit, or a file of another kind (:func:`cable_ocp.result_files.netcdf.read`). The file is
written by the one atomic writer, :func:`cable_ocp.result_files.netcdf.write`.
"""

from __future__ import annotations

import hashlib
import json

import numpy as np
import xarray as xr

from cable_ocp.policy.network import Network
from cable_ocp.policy.observation import FEATURES, UNITS
from cable_ocp.result_files import netcdf
from cable_ocp.result_files.units import cf_units

KIND = "Policy"  # the kind of result the file declares
WHAT = "learned policy"
RATE = cf_units("rad/s")


def to_dataset(policy) -> xr.Dataset:
    """A :class:`~cable_ocp.policy.policy.Policy` as a Dataset (module docstring)."""
    net = policy.network
    variables: dict[str, xr.DataArray] = {}
    for k, (name, unit) in enumerate(zip(FEATURES, UNITS, strict=True)):
        unit = cf_units(unit)
        variables[f"observation_{name}"] = xr.DataArray(
            policy.observations[:, k], dims="sample", attrs={"units": unit}
        )
        variables[f"input_mean_{name}"] = xr.DataArray(net.input_mean[k], attrs={"units": unit})
        variables[f"input_scale_{name}"] = xr.DataArray(net.input_scale[k], attrs={"units": unit})
    variables["action"] = xr.DataArray(
        policy.actions, dims="sample",
        attrs={"units": RATE, "long_name": "The MPC's mean drum rate over the next sample"},
    )  # fmt: skip
    variables["round"] = xr.DataArray(
        np.asarray(policy.rounds, dtype=np.int64), dims="sample", attrs={"units": "1"}
    )
    for k, (w, b) in enumerate(zip(net.weights, net.biases, strict=True)):
        variables[f"weight_{k}"] = xr.DataArray(w, dims=(f"out_{k}", f"in_{k}"),
                                                attrs={"units": "1"})  # fmt: skip
        variables[f"bias_{k}"] = xr.DataArray(b, dims=f"out_{k}", attrs={"units": "1"})
    for name in ("output_mean", "output_scale", "rate_limit"):
        variables[name] = xr.DataArray(float(getattr(net, name)), attrs={"units": RATE})
    return xr.Dataset(
        variables,
        attrs={
            **netcdf.file_attributes(KIND),
            "family": json.dumps(policy.family, sort_keys=True),
            "validation": json.dumps(policy.validation, sort_keys=True),
            "seed": int(policy.seed),
            "margin": float(policy.margin),
            "layers": len(net.weights),
            "features": json.dumps(list(FEATURES)),
            "digest": policy.digest,
            "data_digest": data_digest(policy),
        },
    )


def fields_of(data: xr.Dataset) -> dict:
    """The fields of a Policy from a Dataset of :func:`to_dataset`.

    Raises
    ------
    ValueError
        The features are not this cable_ocp's, a layer is missing or does not fit, or the
        numbers do not hash to the file's digest (damaged).
    """
    attrs = data.attrs
    features = json.loads(attrs.get("features", "[]"))
    if tuple(features) != FEATURES:
        raise ValueError(f"features {features}: this cable_ocp's policies see {list(FEATURES)}")
    layers = int(attrs["layers"])
    network = Network(
        tuple(np.asarray(data[f"weight_{k}"].values, dtype=float) for k in range(layers)),
        tuple(np.asarray(data[f"bias_{k}"].values, dtype=float) for k in range(layers)),
        np.array([float(data[f"input_mean_{name}"]) for name in FEATURES]),
        np.array([float(data[f"input_scale_{name}"]) for name in FEATURES]),
        float(data["output_mean"]),
        float(data["output_scale"]),
        float(data["rate_limit"]),
    )
    observations = np.column_stack([data[f"observation_{name}"].values for name in FEATURES])
    return {
        "network": network,
        "family": json.loads(attrs["family"]),
        "observations": np.asarray(observations, dtype=float),
        "actions": np.asarray(data["action"].values, dtype=float),
        "rounds": np.asarray(data["round"].values, dtype=np.int64),
        "seed": int(attrs["seed"]),
        "validation": json.loads(attrs["validation"]),
        "margin": float(attrs["margin"]),
    }


def data_digest(policy) -> str:
    """SHA-256 (hex) of a policy's training data: observations, actions and rounds."""
    h = hashlib.sha256()
    for array in (policy.observations, policy.actions):
        h.update(np.ascontiguousarray(array, dtype=float).tobytes())
    h.update(np.ascontiguousarray(policy.rounds, dtype=np.int64).tobytes())
    return h.hexdigest()


def check_digest(policy, data: xr.Dataset) -> None:
    """ValueError unless the policy read hashes to the digests its file was written with."""
    for what, found, written in (
        ("network", policy.digest, data.attrs.get("digest")),
        ("training data", data_digest(policy), data.attrs.get("data_digest")),
    ):
        if found != written:
            raise ValueError(
                f"its {what} does not hash to the digest it was written with ({found[:12]} "
                f"against {str(written)[:12]}): a damaged file"
            )
