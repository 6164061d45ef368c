"""Results of a simulation: the :class:`Trajectory`, with saving to npz + json and loading."""

from __future__ import annotations

import json
from dataclasses import dataclass, fields
from pathlib import Path

import numpy as np

ARRAY_FIELDS = (
    "time", "states", "inputs", "joints", "tensions", "winch_angle", "clearance_error",
)  # fmt: skip


@dataclass(frozen=True, eq=False)
class Trajectory:
    """A simulated run, sampled at its output times.

    Attributes
    ----------
    time : array (k,), s
    states : array (k, state_size)
        ``x = [q; q']`` (see ``state_names``).
    inputs : array (k, 15)
        Model inputs (see :data:`cable_ocp.model.INPUT_NAMES`).
    joints : array (k, 3, n+2), m
        Joint positions ``A_0`` (the end E) .. ``A_{n+1}`` (the top).
    tensions : array (k, n+1), N
        Bond forces ``|lambda_j|`` at ``A_1 .. A_{n+1}``; the last is the top tension.
    winch_angle : array (k,), rad
    clearance_error : array (k,), m
        ``e(t)`` of eq. 39.
    omega : float, m
        ``Omega`` of eq. 39.
    scene_name : str
    state_names : list of str
    """

    time: np.ndarray
    states: np.ndarray
    inputs: np.ndarray
    joints: np.ndarray
    tensions: np.ndarray
    winch_angle: np.ndarray
    clearance_error: np.ndarray
    omega: float
    scene_name: str
    state_names: list[str]

    @property
    def end(self) -> np.ndarray:
        """Position of the end E over time (k, 3), m."""
        return self.joints[:, :, 0]

    @property
    def top(self) -> np.ndarray:
        """Position of the top point over time (k, 3), m."""
        return self.joints[:, :, -1]

    @property
    def top_length(self) -> np.ndarray:
        """Length of the top element over time (k,), m."""
        return self.inputs[:, 9]

    @property
    def top_tension(self) -> np.ndarray:
        """Tension at the top (k,), N."""
        return self.tensions[:, -1]

    def save(self, path: str | Path) -> tuple[Path, Path]:
        """Write ``path.npz`` (arrays) and ``path.json`` (scalars and names).

        Returns
        -------
        the two paths written
        """
        path = Path(path)
        arrays = path.with_suffix(".npz")
        meta = path.with_suffix(".json")
        np.savez_compressed(arrays, **{name: getattr(self, name) for name in ARRAY_FIELDS})
        meta.write_text(
            json.dumps(
                {
                    "omega": self.omega,
                    "scene_name": self.scene_name,
                    "state_names": self.state_names,
                },
                indent=1,
            )
        )
        return arrays, meta

    @classmethod
    def load(cls, path: str | Path) -> Trajectory:
        """Read a trajectory written by :meth:`save`."""
        path = Path(path)
        with np.load(path.with_suffix(".npz")) as data:
            arrays = {name: data[name] for name in ARRAY_FIELDS}
        meta = json.loads(path.with_suffix(".json").read_text())
        return cls(**arrays, **meta)

    def equals(self, other: Trajectory) -> bool:
        """Whether every array and value is identical."""
        for f in fields(self):
            a, b = getattr(self, f.name), getattr(other, f.name)
            same = np.array_equal(a, b) if isinstance(a, np.ndarray) else a == b
            if not same:
                return False
        return True
