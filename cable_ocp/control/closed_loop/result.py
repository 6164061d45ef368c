"""The result of a closed-loop run: :class:`MpcResult`, kept as a labelled Dataset in netCDF."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import xarray as xr

from cable_ocp.control.closed_loop import labelled
from cable_ocp.scene import labelled as results
from cable_ocp.scene.schema import scene_of


@dataclass(frozen=True, eq=False)
class MpcResult:
    """A closed-loop run: the plant under the receding-horizon controller.

    Attributes
    ----------
    time : array (k,), s
        The plant's steps.
    winch_angle : array (k,), rad
        The angle applied (heave feedback included, held in the winch range by a soft limiter).
    planned_angle : array (k,), rad
        The controller's plan (commanded angle, before heave feedback).
    end, top : arrays (k, 3), m
        Positions of the end E and of the top point.
    clearance_error : array (k,), m
        ``e(t)`` of eq. 39 on the plant.
    omega : float, m
        Omega of eq. 39 over the run.
    sample_times : array (s,), s
        When the controller solved.
    solve_times : array (s,), s
        Wall time of each solve (Gauss-Newton or IPOPT), without the state estimate.
    iterations : array (s,)
        Iterations of each solve (1 for the real-time iteration).
    statuses : list of str
        The solver's status of each solve.
    failures : list of str
        One line per failed solve (its time and status); the plant then kept the previous plan.
    success : bool
        Every solve succeeded and the plant ran to the end.
    limited_steps : int
        Plant steps at which the soft limiter changed the commanded angle (within
        ``MpcSettings.limiter_band`` of a
        bound, :mod:`.plant`).
    projected_samples : int
        Samples that started from a plant state moved back onto its bonds, its residual having
        crept above half of ``numerics.constraint_tolerance`` (:meth:`.plant.Plant.onto_bonds`).
    angle_range : (float, float), rad
        The winch range the applied angle is held in.
    real_time_factor : float
        Simulated time over the wall time of the loop (controller and plant; > 1 is faster than
        real time). The one-off build of the controller is not in it (``build_time``).
    worst_solve_time : float, s
    wall_time : float, s
        The loop's wall time.
    build_time : float, s
        Building the controller's transcription (compiling or loading its libraries).
    settings : dict
        The fields of :class:`.settings.MpcSettings` (:meth:`.settings.MpcSettings.record`; the
        model's and the solver's as tables), ``derived``, ``plant_elements`` and ``plant_step``
        (s). Files written before the settings were split keep their units in the keys.
    references : dict of str to array (k,)
        Clearance errors of reference runs on the same plant and time grid (``"locked"``,
        ``"open-loop"``, ``"open-loop + heave feedback"``), m.
    reference_omegas : dict of str to float
        Their Omega, m.
    status : str
        How the loop went: the plant's failure (when and why; the arrays then end there), the
        failed solves, reference runs left out.
    scene_record : dict
        The plant's scene, as :meth:`~cable_ocp.scene.schema.Scene.to_dict` gives it (its
        overrides, a heave set by ``--set`` say, applied); :attr:`scene` rebuilds it. Empty in
        files written before it was kept.
    """

    time: np.ndarray
    winch_angle: np.ndarray
    planned_angle: np.ndarray
    end: np.ndarray
    top: np.ndarray
    clearance_error: np.ndarray
    omega: float
    sample_times: np.ndarray
    solve_times: np.ndarray
    iterations: np.ndarray
    statuses: list[str]
    failures: list[str]
    success: bool
    limited_steps: int
    angle_range: tuple[float, float]
    real_time_factor: float
    worst_solve_time: float
    wall_time: float
    build_time: float
    settings: dict
    projected_samples: int = 0
    references: dict[str, np.ndarray] = field(default_factory=dict)
    reference_omegas: dict[str, float] = field(default_factory=dict)
    status: str = ""
    scene_record: dict = field(default_factory=dict)

    @property
    def scene(self):
        """The plant's scene (a validated ``Scene``; see ``scene_record``)."""
        return scene_of(self.scene_record, self.scene_record.get("name", "scene"))

    def summary(self) -> dict:
        """The scalar figures of the run (json-ready)."""
        return {
            "omega_m": self.omega,
            "success": self.success,
            "status": self.status,
            "failed_solves": len(self.failures),
            "failures": self.failures,
            "solves": int(self.sample_times.size),
            "real_time_factor": self.real_time_factor,
            "worst_solve_time_s": self.worst_solve_time,
            "mean_solve_time_s": float(np.mean(self.solve_times)),
            "mean_iterations": float(np.mean(self.iterations)),
            "wall_time_s": self.wall_time,
            "build_time_s": self.build_time,
            "limited_steps": self.limited_steps,
            "projected_samples": self.projected_samples,
            "angle_range_rad": list(self.angle_range),
            "applied_angle_range_rad": [
                float(self.winch_angle.min()),
                float(self.winch_angle.max()),
            ],
            "reference_omegas_m": self.reference_omegas,
            "settings": self.settings,
        }

    def to_xarray(self) -> xr.Dataset:
        """The run as an ``xarray.Dataset`` over (time, component, sample, reference, bound).

        Every variable carries ``units`` and ``long_name``
        (:mod:`cable_ocp.control.closed_loop.labelled`).
        """
        return labelled.to_xarray(self)

    def save(self, folder: str | Path) -> Path:
        """Write the run to netCDF, ``folder/mpc.nc`` (see :meth:`to_xarray`)."""
        folder = Path(folder)
        folder.mkdir(parents=True, exist_ok=True)
        return results.write(self.to_xarray(), folder / labelled.FILE)

    @classmethod
    def load(cls, folder: str | Path) -> MpcResult:
        """Read a run written by :meth:`save` (or ``mpc.json`` + ``mpc.npz`` of cable_ocp 0.1).

        Raises
        ------
        ValueError
            Naming the file, if it is missing, truncated, garbled or of a newer format.
        """
        return labelled.load(cls, Path(folder))
