"""cable_ocp: dynamics and optimal winch control of a cable-suspended load.

The front door: load a scene, build its model, simulate it, optimise its winch
(open loop or closed loop) and sweep scenes on Dask (:mod:`cable_ocp.sweep`). Conventions and
errata: ``cable_ocp/CONVENTIONS.md``.
"""

from cable_ocp import plots
from cable_ocp.control.closed_loop import MpcResult, mpc
from cable_ocp.control.nelder_mead import NelderMeadSettings
from cable_ocp.control.ocp import IpoptSettings
from cable_ocp.control.optimization import OcpResult, optimize
from cable_ocp.drive.drive import Drive
from cable_ocp.model.cable import INPUT_NAMES, CableModel
from cable_ocp.scene.schema import Scene, load_scene
from cable_ocp.simulation.integrate import SimulationError, integrate, reference_solution
from cable_ocp.simulation.run import simulate
from cable_ocp.simulation.statics import EquilibriumError, equilibrium
from cable_ocp.simulation.trajectory import Trajectory
from cable_ocp.studies.catenary import catenary_shape
from cable_ocp.studies.validation import catenary_check

__all__ = [
    "INPUT_NAMES",
    "CableModel",
    "IpoptSettings",
    "MpcResult",
    "NelderMeadSettings",
    "OcpResult",
    "Drive",
    "EquilibriumError",
    "Scene",
    "SimulationError",
    "Trajectory",
    "catenary_check",
    "catenary_shape",
    "equilibrium",
    "integrate",
    "load_scene",
    "mpc",
    "optimize",
    "plots",
    "reference_solution",
    "simulate",
]
