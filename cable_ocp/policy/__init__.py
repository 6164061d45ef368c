"""A learned winch policy: a small network that imitates the MPC, with the MPC as its safety net.

Modules, each one job: ``observation`` (what a winch controller can measure, as one vector),
``action`` (a drum rate over the next sample, read off a plan and made into one), ``network``
(the tanh MLP in numpy and CasADi, trained by L-BFGS), ``c_export`` (the same network as
dependency-free C), ``safety`` (the envelope and bounds checks, the MPC where they fail),
``policy`` (:class:`Policy`: the network with its family, data and figures; ``load_policy``),
``files`` (its netCDF form), ``family`` (a base scene and ranges of its fields), ``data``
((observation, action) pairs along closed-loop runs on Dask, DAgger's rounds included) and
``learn`` (:func:`learn_policy`, the whole of it).

The names below are imported on first use (PEP 562).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from cable_ocp.lazy import lazy_names

if TYPE_CHECKING:  # what __getattr__ imports (lazy_names reads it), for type checkers too
    from cable_ocp.policy.family import Family, bundled_families, load_family
    from cable_ocp.policy.learn import learn_policy
    from cable_ocp.policy.network import Network
    from cable_ocp.policy.observation import FEATURES
    from cable_ocp.policy.policy import Policy, load_policy

__all__ = [
    "FEATURES", "Family", "Network", "Policy", "bundled_families", "learn_policy", "load_family",
    "load_policy",
]  # fmt: skip
__getattr__, __dir__ = lazy_names(globals())
