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

if TYPE_CHECKING:  # what __getattr__ imports, for type checkers and the import graph
    from cable_ocp import plots
    from cable_ocp.control.closed_loop.loop import mpc
    from cable_ocp.control.closed_loop.result import MpcResult
    from cable_ocp.control.closed_loop.settings import MpcSettings
    from cable_ocp.control.gauss_newton import GaussNewtonSettings
    from cable_ocp.control.nelder_mead import NelderMeadSettings
    from cable_ocp.control.ocp import IpoptSettings
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
    from cable_ocp.scene.schema import Scene, load_scene
    from cable_ocp.simulation.integrate import SimulationError, integrate, reference_solution
    from cable_ocp.simulation.line_trajectory import LineTrajectory
    from cable_ocp.simulation.run import simulate
    from cable_ocp.simulation.statics import EquilibriumError, equilibrium
    from cable_ocp.simulation.trajectory import Trajectory
    from cable_ocp.studies.catenary import catenary_shape
    from cable_ocp.studies.validation import catenary_check

# Each public name and the module that defines it ("plots" is a subpackage).
_SOURCES = {
    "INPUT_NAMES": "cable_ocp.model.cable",
    "CableModel": "cable_ocp.model.cable",
    "GaussNewtonSettings": "cable_ocp.control.gauss_newton",
    "GridSettings": "cable_ocp.control.settings",
    "IpoptSettings": "cable_ocp.control.ocp",
    "ModelSettings": "cable_ocp.control.settings",
    "SOLVERS": "cable_ocp.control.solvers",
    "TranscriptionSettings": "cable_ocp.control.settings",
    "MpcResult": "cable_ocp.control.closed_loop.result",
    "MpcSettings": "cable_ocp.control.closed_loop.settings",
    "NelderMeadSettings": "cable_ocp.control.nelder_mead",
    "OcpResult": "cable_ocp.control.optimization",
    "Drive": "cable_ocp.drive.drive",
    "EquilibriumError": "cable_ocp.simulation.statics",
    "LineTrajectory": "cable_ocp.simulation.line_trajectory",
    "Scene": "cable_ocp.scene.schema",
    "SimulationError": "cable_ocp.simulation.integrate",
    "Trajectory": "cable_ocp.simulation.trajectory",
    "catenary_check": "cable_ocp.studies.validation",
    "check_landing": "cable_ocp.lowering.checks",
    "hold": "cable_ocp.lowering.hold",
    "land": "cable_ocp.lowering.landing",
    "landing_scene": "cable_ocp.lowering.landing",
    "plan_landing": "cable_ocp.lowering.plan",
    "catenary_shape": "cable_ocp.studies.catenary",
    "equilibrium": "cable_ocp.simulation.statics",
    "integrate": "cable_ocp.simulation.integrate",
    "load_result": "cable_ocp.lowering.results",
    "load_scene": "cable_ocp.scene.schema",
    "mpc": "cable_ocp.control.closed_loop.loop",
    "optimize": "cable_ocp.control.optimization",
    "plots": "cable_ocp.plots",
    "reference_solution": "cable_ocp.simulation.integrate",
    "simulate": "cable_ocp.simulation.run",
}

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
    "landing_scene",
    "load_result",
    "load_scene",
    "mpc",
    "optimize",
    "plan_landing",
    "plots",
    "reference_solution",
    "simulate",
]
__getattr__, __dir__ = lazy_names(globals(), _SOURCES)
