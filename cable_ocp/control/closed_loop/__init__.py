"""Closed-loop winch control by a receding-horizon OCP (model predictive control).

``mpc(scene, horizon=..., sample=...)`` runs the scene's full model (the plant) under a controller
that solves a multiple-shooting OCP on a reduced model every sample. Modules: ``controller`` (the
NLP), ``projection`` (the state estimate), ``forecast`` (the top forecast), ``plant`` (the plant
and the heave feedback), ``loop`` (the front door), ``result`` (:class:`MpcResult`) and
``labelled`` (its Dataset); its figures are in ``cable_ocp.plots.closed_loop`` and its command in
``cable_ocp.cli.mpc``. The package is not called ``mpc`` so that ``cable_ocp.mpc`` can be the
function.
"""

from cable_ocp.control.closed_loop.loop import mpc
from cable_ocp.control.closed_loop.result import MpcResult

__all__ = ["MpcResult", "mpc"]
