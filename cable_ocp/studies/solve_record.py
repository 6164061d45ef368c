"""What a study keeps of one ``optimize`` run: its figures, without the trajectory."""

from __future__ import annotations

from dataclasses import dataclass, fields

from cable_ocp.control.optimization import OcpResult


@dataclass(frozen=True)
class SolveRecord:
    """The figures of one :class:`~cable_ocp.control.optimization.OcpResult`.

    A study's run record derives from it and adds what it varied.

    Attributes
    ----------
    omega : float, m
        Verified on the scene's own model (NaN when the last iterate could not be simulated).
    omega_model : float, m
        On the optimisation model.
    success : bool
        The solver converged and its profile passed verification.
    status : str
        The solver's own status message, or ``"verification failed: <reason>"``.
    iterations, evaluations : int
        The solver's iterations and objective evaluations (each a simulation for Nelder-Mead).
    wall_time : float, s
        The whole ``optimize`` call, verification included.
    """

    omega: float
    omega_model: float
    success: bool
    status: str
    iterations: int
    evaluations: int
    wall_time: float


def solve_figures(result: OcpResult) -> dict:
    """The fields of :class:`SolveRecord` taken from an ``optimize`` result, by name."""
    return {f.name: getattr(result, f.name) for f in fields(SolveRecord)}
