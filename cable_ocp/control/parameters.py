"""The named parameters of a winch problem: what changes between solves of one transcription.

One transcription (:mod:`cable_ocp.control.shooting`, solved by :mod:`cable_ocp.control.ipopt`
and :mod:`cable_ocp.control.gauss_newton`) serves the open loop, which sets these once from the
scene, and the closed loop, which sets them at every sample from its estimate and forecasts.
They work like rockit's ``ocp.parameter``: declared once with a name and a shape, packed into the
NLP's parameter vector in one place (:func:`pack`) and unpacked as named symbols in one place
(:func:`symbols`).
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import casadi as ca
import numpy as np

from cable_ocp.model.layout import INPUTS


@dataclass(frozen=True)
class ProblemParameters:
    """Values of the named parameters over a horizon of ``K`` RK4 steps.

    Attributes
    ----------
    initial_state : array (nx,)
        State of the optimisation model at the horizon's start.
    top_motion : array (9, 3 K)
        Top position (m), velocity (m/s) and acceleration (m/s^2) at the RK4 stages
        (:func:`cable_ocp.drive.drive.stage_times`).
    winch_base : array (3, 3 K)
        Top-element length (m) with its rate and acceleration before the optimised profile is
        added: the nominal length, and the heave pay-out of eq. 38 where the open loop knows it.
    end_force : array (3, 3 K)
        External force at the free end at the RK4 stages (N): the scene's, or a forecast.
    reference : float, m
        Clearance reference ``z_E(0) - z(x_E(0), y_E(0))`` of the error (CONVENTIONS.md §5).
    end_offset : array (3,)
        Added to the model's end before the error is taken (m): the measured end minus the
        reduced model's (closed loop), zero in the open loop.
    bias : array (K + 1,)
        Added to the clearance error at the RK4 points (m): model correction
        ``e_full - e_reduced`` in the open loop, zero in the closed loop.
    """

    initial_state: np.ndarray
    top_motion: np.ndarray
    winch_base: np.ndarray
    end_force: np.ndarray
    reference: float
    end_offset: np.ndarray
    bias: np.ndarray

    @classmethod
    def from_stage_inputs(
        cls, initial_state: np.ndarray, stage_inputs: np.ndarray, reference: float
    ) -> ProblemParameters:
        """Parameters from stage inputs (15, 3 K), with no end offset and no bias."""
        steps = stage_inputs.shape[1] // 3
        return cls(
            initial_state=np.asarray(initial_state, dtype=float),
            top_motion=stage_inputs[: INPUTS.top_length],
            winch_base=stage_inputs[INPUTS.top_length : INPUTS.end_force.start],
            end_force=stage_inputs[INPUTS.end_force],
            reference=float(reference),
            end_offset=np.zeros(3),
            bias=np.zeros(steps + 1),
        )

    def stage_inputs(self) -> np.ndarray:
        """The fixed stage inputs (15, 3 K): top motion, winch base and end force."""
        return np.vstack([self.top_motion, self.winch_base, self.end_force])

    def same_run(self, other: ProblemParameters) -> bool:
        """Whether the model's run is the same under both: every value equal but the bias."""
        return all(
            np.array_equal(getattr(self, f.name), getattr(other, f.name))
            for f in fields(self)
            if f.name != "bias"
        )

    def pack(self) -> np.ndarray:
        """The NLP's parameter vector (column-major blocks in the order of the fields)."""
        return np.concatenate(
            [np.ravel(getattr(self, f.name), order="F") for f in fields(self)]
        ).astype(float)


def shapes(state_size: int, steps: int) -> dict[str, tuple[int, int]]:
    """Shape of each named parameter for a model of ``state_size`` over ``steps`` RK4 steps."""
    stages = 3 * steps
    return {
        "initial_state": (state_size, 1),
        "top_motion": (9, stages),
        "winch_base": (3, stages),
        "end_force": (3, stages),
        "reference": (1, 1),
        "end_offset": (3, 1),
        "bias": (steps + 1, 1),
    }


def symbols(state_size: int, steps: int) -> tuple[ca.MX, dict[str, ca.MX]]:
    """The NLP's parameter vector and its named parts (reshaped as :func:`shapes`)."""
    layout = shapes(state_size, steps)
    flat = ca.MX.sym("parameters", sum(r * c for r, c in layout.values()))
    named, start = {}, 0
    for name, (rows, columns) in layout.items():
        named[name] = ca.reshape(flat[start : start + rows * columns], rows, columns)
        start += rows * columns
    return flat, named
