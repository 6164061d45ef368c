"""Closed-loop winch control by a receding-horizon OCP (model predictive control).

``mpc(scene, horizon=..., sample=...)`` runs the scene's full model (the plant) under a controller
that solves a multiple-shooting OCP on a reduced model every sample. Modules: ``controller`` (the
NLP), ``projection`` (the state estimate), ``forecast`` (the top forecast), ``plant`` (the plant
and the heave feedback), ``loop`` (the front door), ``result`` (:class:`MpcResult`), ``plots``
and ``command`` (``cable-ocp mpc``).
"""

from cable_ocp.mpc.loop import mpc
from cable_ocp.mpc.result import MpcResult

__all__ = ["MpcResult", "mpc"]
