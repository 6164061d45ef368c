"""A learned winch policy: its network, the family it was learned for, its data and figures.

One object, three forms of the same function: :meth:`Policy.__call__` (numpy),
:meth:`Policy.function` (a CasADi Function, differentiable) and :meth:`Policy.to_c`
(dependency-free C for a controller on board). :meth:`Policy.controller` runs it in a closed
loop with the MPC as its safety net (``co.mpc(scene, policy=policy)``, :mod:`.safety`).
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field
from pathlib import Path

import casadi as ca
import numpy as np
import xarray as xr

from cable_ocp import result_files
from cable_ocp.policy import files
from cable_ocp.policy.c_export import write_c
from cable_ocp.policy.family import Family, load_family
from cable_ocp.policy.network import Network
from cable_ocp.policy.observation import FEATURES
from cable_ocp.policy.safety import MARGIN, Envelope, PolicyController
from cable_ocp.result_files import netcdf


@dataclass(frozen=True, eq=False)
class Policy:
    """A learned winch policy (module docstring).

    Attributes
    ----------
    network : Network
        Observation (:data:`~.observation.FEATURES`) to drum rate, rad/s.
    family : dict
        The family it was learned for (:meth:`.family.Family.record`: its name, base scene,
        ranges and fingerprint).
    observations : array (N, d)
        The training observations (every DAgger round's).
    actions : array (N,), rad/s
        The MPC's drum rate at each (the label).
    rounds : array (N,) of int
        The DAgger round each pair came from (0: the MPC's own runs).
    seed : int
        The seed of the scenes drawn and of the network's initial weights.
    validation : dict
        Figures of its validation (json-ready; empty until validated).
    margin : float
        The envelope's widening (:class:`.safety.Envelope`).
    """

    network: Network
    family: dict
    observations: np.ndarray
    actions: np.ndarray
    rounds: np.ndarray
    seed: int
    validation: dict = field(default_factory=dict)
    margin: float = MARGIN

    @property
    def features(self) -> tuple[str, ...]:
        """The observation's features, in order."""
        return FEATURES

    @property
    def digest(self) -> str:
        """SHA-256 of the network's numbers (hex): two policies alike bit for bit share it."""
        net = self.network
        h = hashlib.sha256()
        for array in (*net.weights, *net.biases, net.input_mean, net.input_scale):
            h.update(np.ascontiguousarray(array, dtype=float).tobytes())
        h.update(np.array([net.output_mean, net.output_scale, net.rate_limit]).tobytes())
        return h.hexdigest()

    @property
    def name(self) -> str:
        """The family's name and the network's digest (12 hex digits)."""
        return f"{self.family.get('name', 'policy')}@{self.digest[:12]}"

    @property
    def envelope(self) -> Envelope:
        """The training observations' envelope."""
        return Envelope.of(self.observations, self.margin)

    def __call__(self, observations: np.ndarray) -> np.ndarray:
        """The drum rate (rad/s) of each observation (rows), clipped to the winch's limit."""
        return self.network(observations)

    def function(self) -> ca.Function:
        """The policy as a CasADi Function ``policy(observation) -> rate``."""
        return self.network.function()

    def to_c(self, path: str | Path) -> tuple[Path, Path]:
        """Write the policy as dependency-free C, ``path`` with ``.c`` and ``.h``.

        The function is ``double cable_ocp_policy(const double observation[])``; the header
        lists the observation's features in order.
        """
        return write_c(self.network, self.features, path)

    def controller(self, parts, net: bool = True) -> PolicyController:
        """The closed loop's step of this policy (``co.mpc(scene, policy=self)`` calls it).

        ``net``: with the safety net (the envelope, the bounds and the reduced model's rollout;
        the MPC where they fail);
        False: the policy alone, whatever it gives.
        """
        if not net:
            return PolicyController(parts, self.network, None, bounds=False, rollout=False)
        return PolicyController(parts, self.network, self.envelope)

    def alone(self) -> Alone:
        """The same policy without its safety net, for ``co.mpc(scene, policy=...)``."""
        return Alone(self)

    def to_xarray(self) -> xr.Dataset:
        """The policy as an ``xarray.Dataset`` (:func:`.files.to_dataset`)."""
        return files.to_dataset(self)

    @classmethod
    def from_xarray(cls, data: xr.Dataset) -> Policy:
        """The policy a Dataset of :meth:`to_xarray` holds; ValueError if it does not fit."""
        return cls(**files.fields_of(data))

    def save(self, path: str | Path) -> Path:
        """Write the policy to the netCDF file ``path`` (atomically); returns the path."""
        return netcdf.write(self.to_xarray(), Path(path))

    @classmethod
    def load(cls, path: str | Path, family=None) -> Policy:
        """:func:`load_policy`."""
        return load_policy(path, family)


def load_policy(path: str | Path, family=None) -> Policy:
    """Read a policy written by :meth:`cable_ocp.policy.policy.Policy.save`.

    Parameters
    ----------
    path : path-like
        The policy's netCDF file.
    family : Family, str or path-like, optional
        The family the policy must have been learned for (a :class:`.family.Family` or its
        file): a policy of another family is refused.

    Raises
    ------
    ValueError
        Naming the file: missing, not a policy, damaged (its numbers do not hash to the digest
        it was written with), or learned for another family than ``family``.
    """
    policy = result_files.load(Policy, path, files.WHAT, files.check_digest)
    if family is not None:
        wanted = family if isinstance(family, Family) else load_family(family)
        found = policy.family.get("fingerprint")
        if found != wanted.fingerprint:
            raise ValueError(
                f"{path}: a policy learned for the family {policy.family.get('name')!r} "
                f"(fingerprint {found}), not for {wanted.name!r} (fingerprint "
                f"{wanted.fingerprint}): learn one for it (cable-ocp learn)"
            )
    return policy


@dataclass(frozen=True)
class Alone:
    """A policy run without its safety net (its validation's "policy alone")."""

    policy: Policy

    @property
    def name(self) -> str:
        """The policy's name, marked as alone."""
        return f"{self.policy.name} (alone)"

    def controller(self, parts) -> PolicyController:
        """The loop's step: the policy's action at every sample."""
        return self.policy.controller(parts, net=False)
