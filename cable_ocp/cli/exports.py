"""Files a results folder carries for other programs: the winch's profile as CSV."""

from __future__ import annotations

import numpy as np

from cable_ocp.model.layout import INPUTS

WINCH_COLUMNS = ("time_s", "winch_angle_rad", "winch_rate_rad_s", "line_out_m", "payout_rate_m_s")


def winch_csv(trajectory, scene) -> str:
    """The verified winch profile as CSV text, one row per output time, for a winch's controller.

    Columns (:data:`WINCH_COLUMNS`): time (s); the drum angle ``phi`` (rad, the heave's pay-out
    included where the scene heaves) and its rate (rad/s); the line out from drum to end,
    ``cable.length + r_D phi`` (m); the pay-out rate ``r_D phi'`` (m/s), as the model was driven.
    """
    radius = scene.winch.drum_radius
    payout_rate = trajectory.inputs[:, INPUTS.top_length_rate]
    table = np.column_stack([
        trajectory.time,
        trajectory.winch_angle,
        payout_rate / radius,
        scene.cable.length + radius * trajectory.winch_angle,
        payout_rate,
    ])  # fmt: skip
    lines = [",".join(WINCH_COLUMNS)]
    lines += [",".join(f"{value:.9g}" for value in row) for row in table]
    return "\n".join(lines) + "\n"
