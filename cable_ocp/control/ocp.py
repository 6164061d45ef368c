"""The old import path of IPOPT's settings and of ``control_of`` (the guide names it).

IPOPT's settings and solver are :mod:`cable_ocp.control.ipopt`'s, the direct-shooting
transcription :mod:`cable_ocp.control.shooting`'s; ``co.IpoptSettings`` is the public name.
"""

from cable_ocp.control.ipopt import IpoptSettings
from cable_ocp.control.shooting import control_of

__all__ = ["IpoptSettings", "control_of"]
