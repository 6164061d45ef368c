"""Shared fixtures of the physics tests: scene paths and state builders."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

MODELS = Path(__file__).resolve().parent.parent / "models"


def axis(psi: float, theta: float) -> np.ndarray:
    """Element direction e(psi, theta) of DESIGN.md §3, written out independently of the package."""
    return np.array([np.cos(theta) * np.cos(psi), np.sin(theta), np.cos(theta) * np.sin(psi)])


def chained_state(model, u: np.ndarray, psi, theta) -> np.ndarray:
    """State at rest with the given element angles, positions chained down from the top point.

    ``A_{n+1} = u[0:3]`` and ``A_i = A_{i+1} - l_i e_i``, so every bond holds exactly. ``psi`` and
    ``theta`` are scalars (a straight line) or one value per element (0..n). Twist angles, if any,
    and all rates are zero.
    """
    count = model.element_count
    psi = np.broadcast_to(np.asarray(psi, dtype=float), (count,))
    theta = np.broadcast_to(np.asarray(theta, dtype=float), (count,))
    lengths = [float(length) for length in model.element_lengths(float(u[9]))]
    q = np.zeros((count, model.dofs))
    point = np.asarray(u[0:3], dtype=float).copy()
    for i in reversed(range(count)):
        point = point - lengths[i] * axis(psi[i], theta[i])
        q[i, :3] = point
        q[i, 3], q[i, 4] = psi[i], theta[i]
    return np.concatenate([q.ravel(), np.zeros(q.size)])


@pytest.fixture(scope="session")
def models_dir() -> Path:
    """The folder of the bundled scene files."""
    return MODELS


@pytest.fixture(scope="session")
def chained():
    """Builder ``(model, u, psi, theta) -> state`` of a chain at rest hanging from the top point."""
    return chained_state


@pytest.fixture(scope="session")
def tilted():
    """Builder ``(model, u) -> state``: the straight line psi = pi/2 + 0.3, theta = 0.1, at rest."""

    def build(model, u, tilt: float = 0.3, theta: float = 0.1) -> np.ndarray:
        return chained_state(model, u, np.pi / 2 + tilt, theta)

    return build
