"""What a study keeps of one ``optimize`` run: its result without the verified trajectory."""

from __future__ import annotations

from dataclasses import replace

from cable_ocp.control.optimization import OcpResult


def kept(result: OcpResult) -> OcpResult:
    """``result`` without its trajectory: its figures, profile and settings, not the whole run.

    A study holds many runs; its tables and charts read the result's figures (``omega``,
    ``success``, ``status``, ``iterations``, ``wall_time``, ...), which the result declares once.
    """
    return replace(result, trajectory=None)
