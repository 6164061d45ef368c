"""cable_ocp: dynamics and optimal winch control of a cable-suspended load.

The front door: load a scene, build its model, simulate it, optimise its winch
(open loop or closed loop), land a load on the seabed and hold it there (:mod:`cable_ocp.lowering`),
and sweep scenes on Dask (:mod:`cable_ocp.sweep`). Conventions and
errata: ``cable_ocp/CONVENTIONS.md``.

The names below are imported on first use (PEP 562): ``import cable_ocp``, which every
``cable-ocp`` command does, costs no SciPy, optimiser or matplotlib import until one is needed
(``cable-ocp simulate`` never loads the optimisers), by :func:`cable_ocp.lazy.lazy_names`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from cable_ocp.lazy import lazy_names

if TYPE_CHECKING:  # what __getattr__ imports (lazy_names reads it), for type checkers too
    from cable_ocp import plots
    from cable_ocp.control.closed_loop.loop import mpc
    from cable_ocp.control.closed_loop.result import MpcResult
    from cable_ocp.control.closed_loop.settings import MpcSettings
    from cable_ocp.control.gauss_newton import GaussNewtonSettings
    from cable_ocp.control.ipopt import IpoptSettings
    from cable_ocp.control.nelder_mead import NelderMeadSettings
    from cable_ocp.control.optimization import OcpResult, optimize
    from cable_ocp.control.settings import GridSettings, ModelSettings, TranscriptionSettings
    from cable_ocp.control.solvers import SOLVERS
    from cable_ocp.drive.drive import Drive
    from cable_ocp.lowering.checks import check_landing
    from cable_ocp.lowering.hold import hold
    from cable_ocp.lowering.landing import land, landing_scene
    from cable_ocp.lowering.plan import plan_landing
    from cable_ocp.lowering.results import load_result
    from cable_ocp.model.cable import INPUT_NAMES, CableModel
    from cable_ocp.policy.learn import learn_policy
    from cable_ocp.policy.policy import Policy, load_policy
    from cable_ocp.scene.schema import Scene, load_scene
    from cable_ocp.simulation.integrate import SimulationError, integrate, reference_solution
    from cable_ocp.simulation.line_trajectory import LineTrajectory
    from cable_ocp.simulation.run import simulate
    from cable_ocp.simulation.statics import EquilibriumError, equilibrium
    from cable_ocp.simulation.trajectory import Trajectory
    from cable_ocp.studies.catenary import catenary_shape
    from cable_ocp.studies.validation import catenary_check

__all__ = [
    "INPUT_NAMES",
    "CableModel",
    "GaussNewtonSettings",
    "GridSettings",
    "IpoptSettings",
    "ModelSettings",
    "SOLVERS",
    "TranscriptionSettings",
    "MpcResult",
    "MpcSettings",
    "NelderMeadSettings",
    "OcpResult",
    "Policy",
    "Drive",
    "EquilibriumError",
    "LineTrajectory",
    "Scene",
    "SimulationError",
    "Trajectory",
    "catenary_check",
    "catenary_shape",
    "check_landing",
    "equilibrium",
    "hold",
    "integrate",
    "land",
    "learn_policy",
    "landing_scene",
    "load_policy",
    "load_result",
    "load_scene",
    "mpc",
    "optimize",
    "plan_landing",
    "plots",
    "reference_solution",
    "simulate",
]
__getattr__, __dir__ = lazy_names(globals())  # the names imported under TYPE_CHECKING
