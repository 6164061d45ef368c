"""Named layouts of the model's vectors, so that no module reads them by position.

The input vector ``u`` (:data:`INPUT_NAMES`) holds the prescribed top motion, the top-element
length set by the winch with its rates, and the external force at the free end; :data:`INPUTS`
gives the index or slice of each quantity, e.g. ``u[INPUTS.end_force]``. The outputs of the model
(:data:`OUTPUT_NAMES`) are read by name from CasADi's named outputs.
"""

from __future__ import annotations

INPUT_NAMES = (
    "top_x", "top_y", "top_z",
    "top_vx", "top_vy", "top_vz",
    "top_ax", "top_ay", "top_az",
    "top_length", "top_length_rate", "top_length_acceleration",
    "end_force_x", "end_force_y", "end_force_z",
)  # fmt: skip
INPUT_SIZE = len(INPUT_NAMES)
OUTPUT_NAMES = (
    "joints",
    "joint_velocities",
    "bond_residual",
    "bond_rate",
    "bond_forces",
    "tensions",
    "accelerations",
)


class InputLayout:
    """Where each quantity sits in the input vector ``u``.

    Attributes
    ----------
    top, top_velocity, top_acceleration : slice
        Top point (m), its velocity (m/s) and acceleration (m/s^2).
    top_length, top_length_rate, top_length_acceleration : int
        Top-element length set by the winch (m) and its rates (m/s, m/s^2).
    end_force : slice
        External force at the free end (N).
    """

    top = slice(0, 3)
    top_velocity = slice(3, 6)
    top_acceleration = slice(6, 9)
    top_length = 9
    top_length_rate = 10
    top_length_acceleration = 11
    end_force = slice(12, 15)

    def __setattr__(self, name: str, value: object) -> None:
        raise AttributeError("the input layout is fixed")


INPUTS = InputLayout()


def top_inputs(u) -> tuple:
    """The top's position, velocity and acceleration and the winch's length with its two rates.

    ``(top, top_velocity, top_acceleration, top_length, top_length_rate,
    top_length_acceleration)`` of an input vector ``u`` (SX or array), by :data:`INPUTS`.
    """
    return (
        u[INPUTS.top],
        u[INPUTS.top_velocity],
        u[INPUTS.top_acceleration],
        u[INPUTS.top_length],
        u[INPUTS.top_length_rate],
        u[INPUTS.top_length_acceleration],
    )
