"""Results of a simulation: the :class:`Trajectory`, kept as a labelled Dataset in netCDF."""

from __future__ import annotations

from dataclasses import dataclass, field, fields
from pathlib import Path
from types import SimpleNamespace
from typing import ClassVar

import numpy as np
import xarray as xr

from cable_ocp import result_files
from cable_ocp.model.layout import INPUT_SIZE, INPUTS
from cable_ocp.result_files import format_1
from cable_ocp.result_files.netcdf import written_here
from cable_ocp.scene.axial_choice import axial_choice
from cable_ocp.scene.records import check_run
from cable_ocp.scene.schema import SceneError, scene_of
from cable_ocp.simulation import trajectory_dataset
from cable_ocp.simulation.seabed import rms_objective
from cable_ocp.simulation.slack import PhysicsChecked

ARRAY_FIELDS = (
    "time", "states", "inputs", "joints", "tensions", "winch_angle", "clearance_error",
)  # fmt: skip
WHAT = "trajectory"
SIGNED_NAME = "bond force along the axis of element i at its upper end A_{i+1} (negative pushes)"
# Relative tolerance of a stored Omega against eq. 39 recomputed from the stored e(t): the same
# float64 arithmetic gives it to a few ulps; another quadrature of the same series to ~1e-12.
OMEGA_RTOL = 1e-9


@dataclass(frozen=True, eq=False)
class Trajectory(PhysicsChecked):
    """A simulated run, sampled at its output times.

    Attributes
    ----------
    time : array (k,), s
    states : array (k, state_size)
        ``x = [q; q']`` (see ``state_names``).
    inputs : array (k, 15)
        Model inputs (see :data:`cable_ocp.model.cable.INPUT_NAMES`).
    joints : array (k, 3, n+2), m
        Joint positions ``A_0`` (the end E) .. ``A_{n+1}`` (the top).
    tensions : array (k, n+1), N
        Bond forces ``|lambda_j|`` at ``A_1 .. A_{n+1}`` (the model's ``tensions``, no sign).
    winch_angle : array (k,), rad
    clearance_error : array (k,), m
        ``e(t)`` of eq. 39.
    omega : float, m
        ``Omega`` of eq. 39.
    scene_name : str
    state_names : list of str
    scene_record : dict
        The scene that ran, as :meth:`~cable_ocp.scene.schema.Scene.to_dict` gives it (its
        overrides applied); empty in files written before it was kept. :attr:`scene` rebuilds it.
    signed_tensions : array (k, n+1), N
        The bond forces along the element axes, positive pulling, negative pushing
        (:func:`~cable_ocp.simulation.slack.signed_tensions`); the last is the top tension. Empty
        in runs written before it was kept (:attr:`kept_signs`).
    bond_residual : float, m
        Largest bond residual of the run's states after the first, as the integration checked
        them: the run's health check (NaN where no integration checked it, as in files written
        before it was kept).
    """

    # The states and inputs are stored split into named quantities, each with its own unit
    # (:mod:`cable_ocp.simulation.trajectory_dataset`).
    UNITS: ClassVar[dict[str, str]] = {
        "time": "s", "joints": "m", "tensions": "N", "winch_angle": "rad",
        "clearance_error": "m", "omega": "m", "signed_tensions": "N", "bond_residual": "m",
    }  # fmt: skip

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
    scene_record: dict = field(default_factory=dict)
    signed_tensions: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    bond_residual: float = float("nan")

    @property
    def scene(self):
        """The scene that ran (a validated ``Scene``), rebuilt from :attr:`scene_record`.

        Raises
        ------
        ValueError
            If the run holds no scene (a file written before scenes were kept).
        """
        return scene_of(self.scene_record, self.scene_name)

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
        return self.inputs[:, INPUTS.top_length]

    @property
    def kept_signs(self) -> bool:
        """Whether the run holds its signed tensions (not in files written before them)."""
        return self.signed_tensions.shape == self.tensions.shape

    @property
    def top_tension(self) -> np.ndarray:
        """Signed tension at the top (k,), N: negative where the top bond pushes.

        The norm ``|lambda_{n+1}|`` in runs that kept no signed tensions.
        """
        return (self.signed_tensions if self.kept_signs else self.tensions)[:, -1]

    def joined(self, values) -> np.ndarray:
        """``values(self)``: the whole-run view, as :meth:`LineTrajectory.joined` gives it."""
        return values(self)

    def padded(self, values) -> np.ndarray:
        """``values(self)``, as :meth:`LineTrajectory.padded` gives a line run's per-bond views."""
        return values(self)

    def summary(self) -> dict:
        """The run's figures (json-ready), with ``"units"``.

        Omega, the end's rise and final position, the signed top tension's range and the
        physics check (``success``, ``status``, ``notes``).
        """
        return run_summary(self)

    def to_xarray(self) -> xr.Dataset:
        """The run as an ``xarray.Dataset`` over (time, element, joint, component, angle).

        Every variable carries ``units`` and ``long_name``
        (:mod:`cable_ocp.simulation.trajectory_dataset`).
        """
        dataset = trajectory_dataset.to_xarray(self)
        if not self.kept_signs:  # nothing to keep: read back as the default
            return dataset.drop_vars("signed_tensions")
        signed = dataset["signed_tensions"].variable
        dataset = dataset.drop_vars("signed_tensions")
        attrs = {**signed.attrs, "long_name": SIGNED_NAME}
        dataset["signed_tensions"] = xr.Variable(("time", "element"), signed.values, attrs)
        return dataset

    def save(self, path: str | Path) -> Path:
        """Write the run to netCDF, ``path.nc`` (see :meth:`to_xarray`); returns the path."""
        return result_files.save(self, Path(path).with_suffix(".nc"))

    @classmethod
    def from_positions(
        cls,
        time: np.ndarray,
        end: np.ndarray,
        top: np.ndarray,
        winch_angle: np.ndarray,
        clearance_error: np.ndarray,
        omega: float,
        scene_record: dict,
    ) -> Trajectory:
        """A run known only by the positions of its end and its top (k, 3; m) over ``time``.

        The closed-loop files of result formats 1 and 2 kept no more of the plant's run. Its
        joints are the end and the top alone, its tensions NaN, its states empty (so it cannot
        be saved again), its inputs NaN but the top's position.
        """
        count = np.shape(time)[0]
        inputs = np.full((count, INPUT_SIZE), np.nan)
        inputs[:, INPUTS.top] = top
        return cls(
            time=np.asarray(time, dtype=float), states=np.zeros((count, 0)), inputs=inputs,
            joints=np.stack([end, top], axis=2), tensions=np.full((count, 1), np.nan),
            winch_angle=winch_angle, clearance_error=clearance_error, omega=omega,
            scene_name=scene_record.get("name", "scene"), state_names=[],
            scene_record=scene_record,
        )  # fmt: skip

    @classmethod
    def from_xarray(cls, dataset: xr.Dataset) -> Trajectory:
        """The trajectory a Dataset of :meth:`to_xarray` holds.

        Raises
        ------
        ValueError, KeyError
            A variable is missing or does not fit, or the arrays do not fit together.
        """
        arrays = trajectory_dataset.from_dataset(dataset, cls)
        _check_shapes({name: arrays[name] for name in ARRAY_FIELDS})
        signed, tensions = arrays["signed_tensions"].shape, arrays["tensions"].shape
        if signed != tensions and np.prod(signed) > 0:
            raise ValueError(f"signed_tensions of shape {signed} do not fit tensions {tensions}")
        return cls(**arrays)

    @classmethod
    def load(cls, path: str | Path) -> Trajectory:
        """Read a trajectory written by :meth:`save` (``path.nc``).

        Results of cable_ocp 0.1 (``path.npz`` and ``path.json``, result format 1) are read
        when there is no ``path.nc``, as they are: they kept no scene, and their Omega is
        0.1's own (:func:`check_recorded` checks netCDF files).

        Raises
        ------
        ValueError
            Naming the file, if it is missing, truncated or garbled, of a newer format, the
            arrays do not fit together, or its figures or scene do not fit its series
            (:func:`check_recorded`: a forged file).
        """
        path = Path(path)
        netcdf = path.with_suffix(".nc")
        if netcdf.exists() or not (path.with_suffix(".npz").exists() or
                                   path.with_suffix(".json").exists()):  # fmt: skip
            return result_files.load(cls, netcdf, WHAT, _check_file)
        arrays_path, meta_path = path.with_suffix(".npz"), path.with_suffix(".json")
        arrays = format_1.read_arrays(arrays_path, WHAT)
        with format_1.blame(arrays_path, WHAT):
            arrays = {name: np.asarray(arrays[name], dtype=float) for name in ARRAY_FIELDS}
            _check_shapes(arrays)
        meta = format_1.read_json(meta_path, WHAT)
        with format_1.blame(meta_path, WHAT):
            meta = _meta_from_json(meta, arrays["states"].shape[1])
        return cls(**arrays, **meta)

    def equals(self, other: Trajectory) -> bool:
        """Whether every array and value is identical (NaN equal to NaN)."""
        for f in fields(self):
            a, b = getattr(self, f.name), getattr(other, f.name)
            if isinstance(a, np.ndarray | float):
                same = np.array_equal(a, b, equal_nan=True)
            else:
                same = a == b
            if not same:
                return False
        return True


def _check_file(run: Trajectory, dataset: xr.Dataset) -> None:
    """:func:`check_recorded` of a run read from its own file (``dataset``)."""
    n = run.tensions.shape[1] - 1
    check_recorded(run, run.time, run.clearance_error, n, written_here(dataset))


def check_recorded(
    run, time: np.ndarray, error: np.ndarray, elements: int | None, strict: bool = True
) -> None:
    """Check a loaded run's figures and scene against its own series (a forged file is refused).

    :func:`check_figures`, and where the run holds its ``scene_record`` (none in files written
    before runs kept their scene): it validates by the scene schema, ``time`` ends at its
    ``numerics.duration``, and where ``elements`` is given (a fixed-``n`` run), the run has its
    ``model.elements`` and is sampled every ``numerics.output_every`` steps of ``numerics.step``.

    A record that no longer validates because of a file of the scene's that this machine lacks
    (a moved grid), or, unless ``strict``, by the present schema (a file written by another
    version of cable_ocp, whose rules may differ), is checked by its numbers as recorded.

    Parameters
    ----------
    run : Trajectory or LineTrajectory
    time : array (k,), s
    error : array (k,), m
        ``e(t)`` of eq. 39.
    elements : int or None
        ``n`` of the run's model (None for a line run, whose ``n`` changes).
    strict : bool
        The file was written by this cable_ocp (:func:`written_here`).

    Raises
    ------
    ValueError
        Naming the variable, its value and what was expected (the caller adds the file).
    """
    _check_start(time)
    if run.scene_record:
        _check_scene(run, time, elements, strict)
    _check_omega(run.omega, time, error)


def check_figures(run: Trajectory) -> None:
    """Check what a run's own series say of it: its time starts at 0, its Omega is eq. 39.

    Part of :func:`check_kept`, for a run kept inside another result (an ``OcpResult``'s
    verified run, a closed loop's plant, which may stop before its scene's end); a run's own
    file is checked further by :func:`check_recorded`.

    Raises
    ------
    ValueError
        Naming the variable, its value and what was expected.
    """
    _check_start(run.time)
    _check_omega(run.omega, run.time, run.clearance_error)


def check_kept(run, strict: bool, whole: bool = True) -> None:
    """Check a run kept inside another result against its own series and scene record.

    :func:`check_figures`, and where the run holds its ``scene_record``: it validates by the
    scene schema (as :func:`check_recorded` says), a fixed-``n`` run has its ``model.elements``,
    and, if ``whole``, its time ends at ``numerics.duration``. Its output grid is not checked
    (an optimum's verified run may have taken a finer step than its scene's).

    ``run`` and ``strict`` are :func:`check_recorded`'s (``strict``: of the file that holds
    the run), and so is the ValueError; ``whole`` says the run went to its scene's end (False
    for a closed loop's plant, which may stop early).
    """
    check_figures(run)
    if run.scene_record:
        elements = run.tensions.shape[1] - 1 if isinstance(run, Trajectory) else None
        _check_scene(run, run.time, elements, strict, whole=whole, grid=False)


def _check_start(time: np.ndarray) -> None:
    if abs(time[0]) > 1e-9 * max(abs(float(time[-1])), 1.0):
        raise ValueError(f"time starts at {time[0]:.9g} s: expected 0 s")


def _check_omega(omega: float, time: np.ndarray, error: np.ndarray) -> None:
    """``omega`` (m) against eq. 39 on ``time`` and ``error``, to :data:`OMEGA_RTOL`."""
    expected = rms_objective(time, error) if time.size > 1 else float("nan")
    same = np.isclose(omega, expected, rtol=OMEGA_RTOL, atol=0.0)
    if not (same or (np.isnan(omega) and np.isnan(expected))):
        raise ValueError(
            f"omega = {omega!r} m: expected {expected!r} m, eq. 39 on its time and clearance_error"
        )


def _check_scene(
    run, time: np.ndarray, elements: int | None, strict: bool, whole: bool = True,
    grid: bool = True,
) -> None:  # fmt: skip
    """The scene checks of :func:`check_recorded` (of :func:`check_kept`: ``whole``, ``grid``)."""
    try:
        scene = run.scene
        numerics, model = scene.numerics, scene.model
    except SceneError as error:
        if strict and not error.path.endswith(".file"):
            raise ValueError(f"scene_record: not a valid scene ({error})") from None
        # The run's numbers are checked against the record's, as they were when it ran.
        record = run.scene_record
        numerics, model = SimpleNamespace(**record["numerics"]), SimpleNamespace(**record["model"])
    if whole and abs(time[-1] - numerics.duration) > 1e-9 * max(numerics.duration, 1.0):
        raise ValueError(
            f"time ends at {time[-1]:.9g} s: expected its scene's numerics.duration = "
            f"{numerics.duration!r} s"
        )
    if elements is None:
        return
    if elements != model.elements:
        raise ValueError(
            f"element: {elements + 1} elements (n = {elements}): expected its scene's "
            f"model.elements = {model.elements} (n + 1 = {model.elements + 1})"
        )
    if not grid:
        return
    every = numerics.output_every * numerics.step
    grid = np.arange(time.size) * every
    if time.size != round(numerics.duration / every) + 1 or not np.allclose(
        time, grid, rtol=0.0, atol=1e-9 * max(numerics.duration, 1.0)
    ):
        raise ValueError(
            f"time: {time.size} samples from {time[0]:g} to {time[-1]:g} s: expected every "
            f"numerics.output_every * numerics.step = {every:g} s over numerics.duration = "
            f"{numerics.duration!r} s"
        )


def run_summary(run) -> dict:
    """The figures of :meth:`Trajectory.summary` of a Trajectory or a LineTrajectory."""
    physics = run.physics.summary()
    end = run.end
    figures = {
        "scene": run.scene_name,
        "rope": _rope(run),
        "omega": run.omega,
        "end_rise": float(end[:, 2].max() - end[0, 2]),
        "final_end_position": end[-1].tolist(),
        **{name: value for name, value in physics.items() if name != "units"},
    }
    units = {"omega": "m", "end_rise": "m", "final_end_position": "m", **physics["units"]}
    return {**figures, "units": units}


def _rope(run) -> str:
    """What the run's rope was along its axis, and why (empty for a run without its scene)."""
    try:
        return axial_choice(run.scene).note
    except ValueError:  # a file written before runs kept their scene
        return ""


def _check_shapes(arrays: dict[str, np.ndarray]) -> None:
    """Raise ValueError unless the arrays of a trajectory have matching shapes.

    Its time must be strictly increasing, and its states and joints finite
    (:func:`cable_ocp.scene.records.check_run`).
    """
    count = arrays["time"].shape[0] if arrays["time"].ndim == 1 else -1
    ndim = {"states": 2, "inputs": 2, "joints": 3, "tensions": 2}
    for name in ARRAY_FIELDS:
        a = arrays[name]
        if a.ndim != ndim.get(name, 1) or a.shape[0] != count:
            raise ValueError(
                f"array {name} of shape {a.shape} does not fit time {arrays['time'].shape}"
            )
    joints, tensions = arrays["joints"].shape, arrays["tensions"].shape
    if joints[1] != 3 or joints[2] != tensions[1] + 1:
        raise ValueError(f"joints of shape {joints} do not fit tensions of shape {tensions}")
    check_run(arrays["time"], {name: arrays[name] for name in ("states", "joints")})


def _meta_from_json(meta, state_size: int) -> dict:
    """The scalars of a trajectory from its JSON (``null`` omega back to NaN); ValueError if bad."""
    if not isinstance(meta, dict) or set(meta) != {"omega", "scene_name", "state_names"}:
        raise ValueError(f"expected the keys omega, scene_name, state_names, got {meta!r:.80}")
    omega, name, names = meta["omega"], meta["scene_name"], meta["state_names"]
    if omega is not None and (isinstance(omega, bool) or not isinstance(omega, int | float)):
        raise ValueError(f"omega = {omega!r:.40}: expected a number or null")
    if not isinstance(name, str):
        raise ValueError(f"scene_name = {name!r:.40}: expected a string")
    if not isinstance(names, list) or not all(isinstance(n, str) for n in names):
        raise ValueError("state_names: expected a list of strings")
    if len(names) != state_size:
        raise ValueError(f"{len(names)} state_names for {state_size} states")
    return {"omega": float("nan") if omega is None else float(omega), "scene_name": name,
            "state_names": names}  # fmt: skip
