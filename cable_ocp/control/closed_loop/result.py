"""The result of a closed-loop run: :class:`MpcResult`, the plant's run and its solves.

The plant's run is a :class:`~cable_ocp.simulation.trajectory.Trajectory`, as an open-loop
``OcpResult`` carries its verified run; the solves are a :class:`SolveLog`, one entry a solve.
Both are kept in the result's netCDF file (:mod:`cable_ocp.result_files`).
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields
from pathlib import Path
from types import MappingProxyType

import numpy as np
import xarray as xr

from cable_ocp import result_files
from cable_ocp.control.optimization import RetimedOptimum
from cable_ocp.drive.winch import (
    check_retime,
    played_then_resting,
    replayed_duration,
    tabulated_angle,
)
from cable_ocp.result_files import dataset, format_1, netcdf
from cable_ocp.result_files.units import units_of
from cable_ocp.scene.records import check_run
from cable_ocp.simulation.trajectory import Trajectory, check_kept


@dataclass(frozen=True, eq=False)
class SolveLog:
    """The controller's solves, one entry a solve (a sample).

    Attributes
    ----------
    sample_time : array (s,), s
        When the controller solved.
    solve_time : array (s,), s
        Wall time of each solve (Gauss-Newton or IPOPT), without the state estimate.
    iterations : array (s,)
        Iterations of each solve (1 for the real-time iteration).
    status : list of str
        The solver's status of each solve.
    by_policy : array of bool (s,)
        A learned policy acted at the sample (its action, not a solve; ``co.mpc(scene,
        policy=...)``); all False without a policy, and in files written before policies.
    """

    # CF units of the fields kept as variables (result_files.units).
    UNITS = MappingProxyType({
        "sample_time": "s", "solve_time": "s", "iterations": "1", "by_policy": "1",
    })  # fmt: skip

    sample_time: np.ndarray
    solve_time: np.ndarray
    iterations: np.ndarray
    status: list[str]
    by_policy: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))

    def __post_init__(self):
        if not len(self.by_policy):  # none given, or a file written before policies
            object.__setattr__(self, "by_policy", np.zeros(len(self.sample_time), dtype=bool))

    def to_xarray(self) -> xr.Dataset:
        """The solves as a Dataset over ``solve``."""
        names = ("sample_time", "solve_time", "iterations", "by_policy")
        return dataset.to_dataset(self, type(self).__name__, dict.fromkeys(names, ("solve",)))

    @classmethod
    def from_xarray(cls, data: xr.Dataset) -> SolveLog:
        """The solves a Dataset of :meth:`to_xarray` holds; ValueError if they do not fit."""
        values = dataset.from_dataset(cls, data)
        if "by_policy" in values:
            values["by_policy"] = np.asarray(values["by_policy"], dtype=bool)
        names = ("solve_time", "iterations", "status", "by_policy")
        sizes = {name: len(values[name]) for name in names if name in values}
        sizes["by_policy"] = sizes.get("by_policy") or len(values["sample_time"])
        if any(size != len(values["sample_time"]) for size in sizes.values()):
            raise ValueError(f"{sizes} entries for {len(values['sample_time'])} sample times")
        return cls(**values)


@dataclass(frozen=True, eq=False)
class MpcResult(result_files.KeptInFolder):
    """A closed-loop run: the plant under the receding-horizon controller.

    Attributes
    ----------
    trajectory : Trajectory
        The plant's run at its steps, as ``OcpResult.trajectory`` holds an open-loop run: its
        states, inputs, joints and tensions, the winch angle applied (heave feedback
        included, held in the winch range by a soft limiter), ``e(t)`` of eq. 39 and Omega,
        and the plant's scene (its overrides, a heave set by ``--set`` say, applied).
    planned_angle : array (k,), rad
        The controller's plan at the plant's steps (commanded angle, before heave feedback).
    solves : SolveLog
        Each solve: its sample time, wall time, iterations and status.
    failures : list of str
        One line per failed solve (its time and status); the plant then kept the previous plan.
    success : bool
        Every solve succeeded and the plant ran to the end.
    status : str
        How the loop went: the plant's failure (when and why; the run then ends there), the
        failed solves, solves on the winch's own range, the drum's saturation.
    iterations : int
        Iterations of all the solves.
    solve_time : float, s
        Time inside the solver, all the solves.
    worst_solve_time : float, s
        The longest solve.
    limited_steps : int
        Plant steps at which the soft limiter changed the commanded angle (within
        ``MpcSettings.limiter_band`` of a bound, :mod:`.plant`).
    projected_samples : int
        Samples that started from a plant state moved back onto its bonds, its residual having
        crept above half of ``numerics.constraint_tolerance`` (:meth:`.plant.Plant.onto_bonds`).
    angle_range : (float, float), rad
        The winch range the applied angle is held in.
    real_time_factor : float
        Simulated time over the wall time of the loop (controller and plant; > 1 is faster than
        real time). The one-off build of the controller is not in it (``build_time``).
    wall_time : float, s
        The loop's wall time.
    build_time : float, s
        Building the controller's transcription (compiling or loading its libraries).
    saturated_steps : int
        Plant steps in which the drum was held at the winch's rate or acceleration limit
        (``winch.rate_max``, ``winch.acceleration_max``; :mod:`.drum`).
    saturation : str
        When and how long the drum saturated (empty if never).
    settings : dict
        The fields of :class:`.settings.MpcSettings` (:meth:`.settings.MpcSettings.record`; the
        model's and the solver's as tables, :meth:`.settings.MpcSettings.from_record` rebuilds
        them), ``derived`` (how the settings left unset were derived), ``plant_elements`` and
        ``plant_step`` (s). Files written before the settings were split keep their units in
        the keys (``sample_s``).
    """

    FILE, WHAT, FORMAT_1 = "mpc.nc", "closed-loop result", "mpc.json"  # save/load

    # CF units of the fields kept as variables (result_files.units).
    UNITS = MappingProxyType({
        "planned_angle": "rad", "success": "1", "iterations": "1", "solve_time": "s",
        "worst_solve_time": "s", "limited_steps": "1", "projected_samples": "1",
        "angle_range": "rad", "real_time_factor": "1", "wall_time": "s", "build_time": "s",
        "saturated_steps": "1",
    })  # fmt: skip
    trajectory: Trajectory
    planned_angle: np.ndarray
    solves: SolveLog
    failures: list[str]
    success: bool
    status: str
    iterations: int
    solve_time: float
    worst_solve_time: float
    limited_steps: int
    projected_samples: int
    angle_range: tuple[float, float]
    real_time_factor: float
    wall_time: float
    build_time: float
    settings: dict
    saturated_steps: int = 0
    saturation: str = ""

    # The plant's run, as a closed loop's figures and notebooks read it (one copy: the trajectory).
    @property
    def time(self) -> np.ndarray:
        """The plant's steps (k,), s."""
        return self.trajectory.time

    @property
    def duration(self) -> float:
        """The closed loop's horizon (s): its plant's last step."""
        return float(self.trajectory.time[-1])

    def winch_profile(self, scene=None, retime: str | None = None):
        """The drum's angle that the plant applied, as ``t -> (phi, phi', phi'')``, to replay.

        The plant's drum at its steps (the plan, the heave feedback and the drum's limits), through
        a C2 spline (:func:`~cable_ocp.drive.winch.tabulated_angle`): ``co.simulate(scene,
        winch=result)`` drives the winch open loop as the closed loop did.

        Parameters
        ----------
        scene : Scene, optional
            The scene to drive (default: :attr:`scene`).
        retime : {None, "hold", "stretch"}
            As :meth:`cable_ocp.control.optimization.OcpResult.winch_profile`: another duration
            is refused unless retimed (:meth:`retimed`).
        """
        scene = scene if scene is not None else self.scene
        if scene.top.heave_compensated:
            raise ValueError(
                "top.heave.compensation = true: the closed loop's drum angle already holds its "
                "heave feedback; replay it on a scene without the compensation"
            )
        duration = scene.numerics.duration
        own = replayed_duration(self.duration, duration, retime, "result.retimed({})")
        run = self.trajectory
        profile = tabulated_angle(run.time * own / self.duration, run.winch_angle)
        return played_then_resting(profile, own) if own < duration else profile

    def retimed(self, retime: str) -> RetimedOptimum:
        """The applied winch to replay on a scene of another duration as ``retime`` says."""
        check_retime(retime)
        return RetimedOptimum(self, retime)

    def winch_angle(self, t) -> np.ndarray:
        """The drum's angle (rad) applied at the times ``t`` (s), as ``OcpResult.winch_angle``.

        Linear between the plant's steps (exact on them; ``trajectory.winch_angle`` holds them),
        held at the ends outside the run.
        """
        run = self.trajectory
        return np.interp(np.atleast_1d(np.asarray(t, dtype=float)), run.time, run.winch_angle)

    @property
    def clearance_error(self) -> np.ndarray:
        """``e(t)`` of eq. 39 on the plant (k,), m."""
        return self.trajectory.clearance_error

    @property
    def end(self) -> np.ndarray:
        """Position of the end E (k, 3), m."""
        return self.trajectory.end

    @property
    def top(self) -> np.ndarray:
        """Position of the top point (k, 3), m."""
        return self.trajectory.top

    @property
    def omega(self) -> float:
        """Omega of eq. 39 over the run, m (NaN for a plant that failed in its first sample)."""
        return self.trajectory.omega

    @property
    def handed_share(self) -> float:
        """Share of the samples that a learned policy's safety net handed to the MPC.

        NaN for a run without a policy (``settings["policy"]`` names the policy that ran).
        """
        log = self.solves.by_policy
        if not self.settings.get("policy") or not log.size:
            return float("nan")
        return 1.0 - float(np.mean(log))

    @property
    def scene_record(self) -> dict:
        """The plant's scene as :meth:`~cable_ocp.scene.schema.Scene.to_dict` gives it."""
        return self.trajectory.scene_record

    @property
    def scene(self):
        """The plant's scene, its overrides applied (:attr:`Trajectory.scene`, which may raise)."""
        return self.trajectory.scene

    def setting(self, name: str):
        """The setting ``name`` of :attr:`settings` (whose key may carry its unit: ``_s``).

        Raises
        ------
        KeyError
            If the settings hold none of that name.
        """
        for key, value in self.settings.items():
            if key == name or key.rpartition("_")[0] == name:
                return value
        raise KeyError(f"the result's settings hold no {name}")

    def summary(self) -> dict:
        """The scalar figures of the run (json-ready), named as its fields.

        Named as in ``OcpResult.summary`` where the quantity is the same (``omega``,
        ``success``, ``status``, ``iterations``, ``solve_time``, ``wall_time``,
        ``build_time``); ``"units"`` gives the unit of each figure that has one.
        """
        solves = self.solves
        figures = {
            "omega": self.omega,
            "success": self.success,
            "status": self.status,
            "failed_solves": len(self.failures),
            "failures": self.failures,
            "solves": int(solves.sample_time.size),
            "iterations": self.iterations,
            "mean_iterations": float(np.mean(solves.iterations)),
            "solve_time": self.solve_time,
            "mean_solve_time": float(np.mean(solves.solve_time)),
            "worst_solve_time": self.worst_solve_time,
            "real_time_factor": self.real_time_factor,
            "wall_time": self.wall_time,
            "build_time": self.build_time,
            "handed_share": self.handed_share,
            "limited_steps": self.limited_steps,
            "projected_samples": self.projected_samples,
            "saturated_steps": self.saturated_steps,
            "saturated_time": (
                self.saturated_steps * self.setting("plant_step") if self.saturated_steps else 0.0
            ),
            "saturation": self.saturation,
            "angle_range": list(self.angle_range),
            "applied_angle_range": [
                float(np.min(self.trajectory.winch_angle)),
                float(np.max(self.trajectory.winch_angle)),
            ],  # fmt: skip
            "settings": self.settings,
        }
        units = {**units_of(type(self), figures), "omega": "m", "mean_solve_time": "s",
                 "applied_angle_range": "rad", "saturated_time": "s",
                 "handed_share": "1"}  # fmt: skip
        if self.trajectory.kept_signs:  # the plant's signed top tension (simulation.slack)
            slack = self.trajectory.physics.slack
            tensions = {"top_tension_min": slack.least_top_tension,
                        "top_tension_max": slack.peak_top_tension,
                        "least_bond_tension": slack.least_bond_tension}  # fmt: skip
            figures |= tensions
            units |= dict.fromkeys(tensions, "N")
        return {**figures, "units": units}

    def to_xarray(self) -> xr.Dataset:
        """The run as an ``xarray.Dataset``, the plant's trajectory over ``time`` included.

        The trajectory's variables are named as ``Trajectory.to_xarray`` names them, the plan
        lies over ``time``, the solves over ``solve`` (``solves_...`` where a name is the
        result's too), the winch range over ``bound``; failures and settings are attributes
        (JSON).

        Every variable carries ``units`` and ``long_name``.
        """
        dims = {"planned_angle": ("time",), "angle_range": ("bound",)}
        return dataset.to_dataset(self, type(self).__name__, dims, {"bound": ("min", "max")})

    @classmethod
    def from_xarray(cls, data: xr.Dataset) -> MpcResult:
        """The run a Dataset of :meth:`to_xarray` holds, or a file of format 2.

        Format 2 held the run as its end and top over time and the solves as
        ``sample_times``, ``solve_times``, ... (:func:`_format_2`).

        Raises
        ------
        ValueError, KeyError, TypeError
            A field is missing or does not fit, or the plant's run does not fit its own series
            and scene (:func:`~cable_ocp.simulation.trajectory.check_kept`; a success ends at
            its scene's ``numerics.duration``): a forged file.
        """
        if netcdf.format_of(data) == 2:
            return _format_2(cls, data)
        values = dataset.from_dataset(cls, data)
        # A plant that stopped early ends before its scene's end; a success ran to it.
        check_kept(values["trajectory"], netcdf.written_here(data), whole=values["success"])
        _check_plan(values["planned_angle"], values["trajectory"].time)
        return cls(**values)

    @classmethod
    def read_format_1(cls, folder: Path) -> MpcResult:
        """The run of cable_ocp 0.1's ``mpc.json`` + ``mpc.npz`` in ``folder``."""
        return _format_1(cls, folder)


MPC_FILE, WHAT = MpcResult.FILE, MpcResult.WHAT


def _check_plan(planned: np.ndarray, time: np.ndarray) -> None:
    if np.shape(planned) != np.shape(time):
        raise ValueError(
            f"planned_angle of shape {np.shape(planned)} does not fit time {np.shape(time)}"
        )


# --- files of the earlier formats: the run as its end and top over time ------------------------

# Fields of the earlier formats' MpcResult that the present one keeps under the same name.
KEPT = ("failures", "success", "status", "worst_solve_time", "limited_steps",
        "projected_samples", "angle_range", "real_time_factor", "wall_time", "build_time",
        "settings")  # fmt: skip


@dataclass(frozen=True, eq=False)
class _Earlier:
    """An MpcResult as formats 1 and 2 held it (the fields that changed since; see MpcResult).

    Attributes
    ----------
    time : array (k,), s
    winch_angle, planned_angle : arrays (k,), rad
    end, top : arrays (k, 3), m
    clearance_error : array (k,), m
    omega : float, m
    sample_times, solve_times : arrays (s,), s
    iterations : array (s,)
    statuses : list of str
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
    scene_record: dict = field(default_factory=dict)


def _from_earlier(cls, earlier: _Earlier, kept: dict) -> MpcResult:
    """The present MpcResult of a run of format 1 or 2.

    Its plant's run is known by its end and top alone (:meth:`Trajectory.from_positions`).
    """
    for name in ("winch_angle", "planned_angle", "clearance_error", "end", "top"):
        if np.shape(getattr(earlier, name))[:1] != np.shape(earlier.time):
            raise ValueError(
                f"{name} of shape {np.shape(getattr(earlier, name))} does not fit time "
                f"{np.shape(earlier.time)}"
            )
    check_run(earlier.time, {"end": earlier.end, "top": earlier.top})
    run = Trajectory.from_positions(
        earlier.time, earlier.end, earlier.top, earlier.winch_angle, earlier.clearance_error,
        earlier.omega, earlier.scene_record,
    )  # fmt: skip
    solves = SolveLog(earlier.sample_times, earlier.solve_times, earlier.iterations,
                      earlier.statuses)  # fmt: skip
    return cls(
        trajectory=run, planned_angle=earlier.planned_angle, solves=solves,
        iterations=int(np.sum(earlier.iterations)), solve_time=float(np.sum(earlier.solve_times)),
        **kept,
    )  # fmt: skip


def _kept_fields(cls, values: dict) -> dict:
    """The fields of ``cls`` that the earlier formats kept by name (the defaults where not)."""
    defaults = {"projected_samples": 0, "status": ""}
    hints = {f.name for f in fields(cls)}
    return {name: values.get(name, defaults.get(name)) for name in KEPT if name in hints}


def _format_2(cls, data: xr.Dataset) -> MpcResult:
    """An MpcResult from a netCDF file of format 2."""
    earlier = dataset.from_dataset(_Earlier, data)
    kept = dataset.from_dataset(_Format2Kept, data)
    return _from_earlier(cls, _Earlier(**earlier), _kept_fields(cls, kept))


@dataclass(frozen=True, eq=False)
class _Format2Kept:
    """The fields of format 2 that the present MpcResult keeps (their types, for the checks)."""

    failures: list[str]
    success: bool
    limited_steps: int
    angle_range: tuple[float, float]
    real_time_factor: float
    worst_solve_time: float
    wall_time: float
    build_time: float
    settings: dict
    saturated_steps: int = 0
    saturation: str = ""
    projected_samples: int = 0
    status: str = ""


# Format 1 (cable_ocp 0.1): mpc.json held the summary under these names, mpc.npz the arrays.
FORMAT_1_NAMES = {
    "omega_m": "omega", "real_time_factor": "real_time_factor",
    "worst_solve_time_s": "worst_solve_time", "wall_time_s": "wall_time",
    "build_time_s": "build_time", "limited_steps": "limited_steps", "success": "success",
    "failures": "failures", "statuses": "statuses", "settings": "settings", "status": "status",
}  # fmt: skip
FORMAT_1_WHAT = f"{WHAT} of format 1 (mpc.json + mpc.npz, cable_ocp 0.1)"


def _format_1(cls, folder: Path) -> MpcResult:
    """An MpcResult from ``mpc.json`` and ``mpc.npz`` (its reference runs are left out)."""
    path = folder / "mpc.json"
    meta = format_1.read_json(path, FORMAT_1_WHAT)
    with format_1.blame(path, FORMAT_1_WHAT):
        values = {field: meta[name] for name, field in FORMAT_1_NAMES.items() if name in meta}
        values["angle_range"] = tuple(float(v) for v in meta["angle_range_rad"])
    path = folder / "mpc.npz"
    arrays = format_1.read_arrays(path, FORMAT_1_WHAT)
    with format_1.blame(path, FORMAT_1_WHAT):
        arrays = {k: v for k, v in arrays.items() if not k.startswith("reference ")}
        names = {f.name for f in fields(_Earlier)}
        earlier = _Earlier(**{k: v for k, v in {**values, **arrays}.items() if k in names})
        return _from_earlier(cls, earlier, _kept_fields(cls, values))
