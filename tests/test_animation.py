"""co.plots.animate: a GIF of the cable, the end's path and the seabed over time."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

import cable_ocp as co
from cable_ocp.simulation.trajectory import Trajectory
from cable_ocp.simulation.trajectory_dataset import state_names


def _towed(k: int = 30, n: int = 3) -> Trajectory:
    """A straight cable towed along x over a seabed that rises under the end."""
    time = np.linspace(0.0, 29.0, k)
    heights = np.linspace(-50.0, 0.0, n + 2)
    joints = np.zeros((k, 3, n + 2))
    joints[:, 0] = time[:, None] + 0.2 * heights[None, :]
    joints[:, 2] = heights[None, :]
    ground = 2.0 * np.exp(-(((joints[:, 0, 0] - 15.0) / 5.0) ** 2))
    return Trajectory(time=time, states=np.zeros((k, 10 * (n + 1))), inputs=np.zeros((k, 15)),
                      joints=joints, tensions=np.ones((k, n + 1)), winch_angle=np.zeros(k),
                      clearance_error=-ground, omega=0.0, scene_name="towed",
                      state_names=state_names(n + 1, 5))  # fmt: skip


def test_animate_writes_a_gif_of_the_run(tmp_path):
    animation = co.plots.animate(_towed(), path=tmp_path / "tow.gif", frames=5, fps=5)
    with Image.open(tmp_path / "tow.gif") as image:
        assert image.format == "GIF" and image.n_frames == 5
    # The seabed drawn is the one under the end (eq. 39): it rises by the hill's 2 m.
    ax = animation._fig.axes[0]
    seabed = ax.collections[0].get_paths()[0].vertices[:, 1]
    assert seabed.max() - np.median(seabed) == pytest.approx(2.0, abs=0.05)


def test_animate_refuses_no_frames():
    with pytest.raises(ValueError, match="frames = 0"):
        co.plots.animate(_towed(), frames=0)
