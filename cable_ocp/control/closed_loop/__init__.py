"""Closed-loop winch control by a receding-horizon OCP (model predictive control).

``mpc(scene, MpcSettings(...))`` runs the scene's full model (the plant) under a controller that
solves the open loop's winch problem over a receding horizon on a reduced model at every sample.
Modules, in the order of one sample: ``estimator`` (the plant's measurements to the controller's
view, with ``projection`` for the reduced state and ``forecast`` for the top), ``controller``
(the receding-horizon problem and its solver), ``plant`` (the plant and the heave feedback);
``loop`` is the front door (the loop alone), ``settings`` holds :class:`MpcSettings`,
``result`` :class:`MpcResult` (the plant's run as a ``Trajectory``, the solves as a
:class:`SolveLog`), ``references`` the runs a loop is judged against (:func:`reference_runs`:
the winch locked, the open-loop optimum). Its figures are those of ``cable_ocp.plots``, and its
command is in
``cable_ocp.cli.mpc``. The package is not
called ``mpc`` so that ``cable_ocp.mpc`` can be the function.

A loop of one's own steps the parts that :func:`loop_parts` builds as :func:`~.loop.mpc` does:
``estimate = estimator.make_step(measured, angle, rate)``, ``solve = controller.make_step(now,
estimate, angle, rate)``, ``command.make_step(now, solve, estimate)``, ``measured =
plant.make_step(angle, until)`` (:class:`Estimator`, :class:`RecedingHorizon`,
:class:`WinchCommand`, :class:`Plant`, :class:`Measurement`).

The names below are imported on first use (PEP 562), so that the command line reads the settings'
defaults without loading the solvers.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from cable_ocp.lazy import lazy_names

if TYPE_CHECKING:  # what __getattr__ imports (lazy_names reads it), for type checkers too
    from cable_ocp.control.closed_loop.command import WinchCommand
    from cable_ocp.control.closed_loop.controller import RecedingHorizon
    from cable_ocp.control.closed_loop.estimator import Estimator
    from cable_ocp.control.closed_loop.loop import LoopParts, loop_parts, mpc
    from cable_ocp.control.closed_loop.plant import Measurement, Plant
    from cable_ocp.control.closed_loop.references import ReferenceRuns, reference_runs
    from cable_ocp.control.closed_loop.result import MpcResult, SolveLog
    from cable_ocp.control.closed_loop.settings import MpcSettings

__all__ = [
    "Estimator", "LoopParts", "Measurement", "MpcResult", "MpcSettings", "Plant",
    "RecedingHorizon", "ReferenceRuns", "SolveLog", "WinchCommand", "loop_parts", "mpc",
    "reference_runs",
]  # fmt: skip
__getattr__, __dir__ = lazy_names(globals())
