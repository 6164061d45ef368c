"""A run whose number of elements changes: one :class:`Trajectory` per segment of constant ``n``.

Each segment is an ordinary trajectory (its own ``element`` and ``joint`` dimensions); where
``n`` changes, the instant of the change ends one segment (the state before) and starts the
next (the state after), so a jump across a split or a merge reads off the two. The whole-run
views (:attr:`LineTrajectory.time`, :attr:`end`, ...) take each instant once, after the change.
Saved as one netCDF file: the whole-run views at its root, each segment in a group
``segment_K`` as :meth:`Trajectory.to_xarray` writes it (CONVENTIONS.md §2).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import xarray as xr

from cable_ocp.model.layout import INPUTS
from cable_ocp.result_files import netcdf
from cable_ocp.simulation.slack import PhysicsChecked
from cable_ocp.simulation.trajectory import Trajectory, check_recorded, run_summary

KIND = "LineTrajectory"
# The whole-run views that the file's root holds beside its segments.
VIEWS = ("element_count", "line_out", "top_length", "end", "top_tension")


def _joined(name: str, doc: str) -> property:
    """A whole-run view of the segments' attribute ``name``, by :meth:`LineTrajectory.joined`."""
    return property(lambda self: self.joined(lambda s: getattr(s, name)), doc=doc)


@dataclass(frozen=True, eq=False)
class LineTrajectory(PhysicsChecked):
    """A run of a line on the drum (``[winch.line]``), segment by segment.

    Attributes
    ----------
    segments : list of Trajectory
        In time order; segment ``k + 1`` starts at the time segment ``k`` ends.
    element_length : float, m
        ``Delta`` of the line's mesh.
    bond_residual : float, m
        Largest bond residual of the run's states after the first, as integration checked them
        (NaN when loaded from a file).
    """

    segments: list[Trajectory]
    element_length: float
    bond_residual: float = float("nan")

    def joined(self, values) -> np.ndarray:
        """``values(segment)`` (an array per segment, samples first) as one array over the run.

        A change's instant ends one segment and starts the next: it is kept once, from the
        segment after it (the state after the change).
        """
        parts = [values(s) for s in self.segments]
        return np.concatenate([p[:-1] for p in parts[:-1]] + [parts[-1]])

    time = _joined("time", "Output times (k,), s, each once.")

    @property
    def element_count(self) -> np.ndarray:
        """``n`` at each output (k,): the model has ``n + 1`` elements."""
        return self.joined(lambda s: np.full(s.time.size, s.tensions.shape[1] - 1))

    top_length = _joined("top_length", "Length of the top element (k,), m.")

    @property
    def line_out(self) -> np.ndarray:
        """The modelled line out ``(n - 1/2) Delta + l_n`` (k,), m."""
        return (self.element_count - 0.5) * self.element_length + self.top_length

    end = _joined("end", "Position of the end E (k, 3), m.")

    def padded(self, values) -> np.ndarray:
        """``values(segment)`` joined over the run, padded with NaN past each sample's top.

        ``values`` gives an array per segment, samples first and bonds or joints last; each is
        padded to the largest ``n`` of the run.
        """
        width = max(values(s).shape[-1] for s in self.segments)

        def padded(s: Trajectory) -> np.ndarray:
            own = values(s)
            out = np.full((*own.shape[:-1], width), np.nan)
            out[..., : own.shape[-1]] = own
            return out

        return self.joined(padded)

    @property
    def joints(self) -> np.ndarray:
        """Joint positions ``A_0 .. A_{n+1}`` (k, 3, largest n + 2), m, NaN past each top.

        A sample of fewer elements than the largest is padded after its top joint, so that
        plotting a sample draws its own joints and nothing else.
        """
        return self.padded(lambda s: s.joints)

    @property
    def signed_tensions(self) -> np.ndarray:
        """Signed bond tensions (k, largest n + 1), N, NaN past each top (see ``Trajectory``)."""
        return self.padded(lambda s: s.signed_tensions)

    @property
    def scene_name(self) -> str:
        """The scene's name."""
        return self.segments[0].scene_name

    top = _joined("top", "Position of the top point (k, 3), m.")

    top_tension = _joined("top_tension", "Signed tension at the top (k,), N.")

    winch_angle = _joined("winch_angle", "Drum angle (k,), rad.")

    clearance_error = _joined("clearance_error", "``e(t)`` of eq. 39 (k,), m.")

    @property
    def omega(self) -> float:
        """``Omega`` of eq. 39 over the whole run, m."""
        return self.segments[0].omega

    @property
    def scene_record(self) -> dict:
        """The scene that ran, as ``Trajectory.scene_record`` (every segment holds it)."""
        return self.segments[0].scene_record

    @property
    def scene(self):
        """The scene that ran."""
        return self.segments[0].scene

    def summary(self) -> dict:
        """As :meth:`Trajectory.summary`, with the line out's range (m)."""
        figures = run_summary(self)
        line = self.line_out
        units = {**figures.pop("units"), "line_out_range": "m"}
        return {**figures, "line_out_range": [float(line.min()), float(line.max())], "units": units}

    def element_lengths(self, segment: int) -> np.ndarray:
        """Lengths ``l_0 .. l_n`` (k, n+1) of the elements of a segment over its times, m."""
        s = self.segments[segment]
        n = s.tensions.shape[1] - 1
        lengths = np.full((s.time.size, n + 1), self.element_length)
        lengths[:, 0] = self.element_length / 2
        lengths[:, -1] = s.inputs[:, INPUTS.top_length]
        return lengths

    def to_xarray(self) -> xr.Dataset:
        """The whole-run views over ``time`` (the segments are in :meth:`save`'s groups)."""
        return xr.Dataset(
            {
                "element_count": ("time", self.element_count, _cf("1", "n, elements 0..n")),
                "line_out": ("time", self.line_out, _cf("m", "line out")),
                "top_length": ("time", self.top_length, _cf("m", "length of the top element")),
                "end": (("time", "component"), self.end, _cf("m", "position of the end E")),
                "top_tension": ("time", self.top_tension, _cf("N", "signed tension at the top")),
            },
            coords={
                "time": ("time", self.time, _cf("s", "time")),
                "component": ("component", ["x", "y", "z"], _cf("1", "component (z up)")),
            },
            attrs={
                **netcdf.file_attributes(KIND),
                "segments": len(self.segments),
                "element_length": self.element_length,
            },
        )

    def save(self, path: str | Path) -> Path:
        """Write ``path.nc``: the whole-run views at its root, segment ``K`` in group ``segment_K``.

        Returns the path.
        """
        path = Path(path).with_suffix(".nc")
        groups = {f"segment_{k}": s.to_xarray() for k, s in enumerate(self.segments)}
        return netcdf.write(self.to_xarray(), path, groups)

    @classmethod
    def load(cls, path: str | Path) -> LineTrajectory:
        """Read a file written by :meth:`save`.

        Files written before line trajectories carried the result format (their kind in
        ``cable_ocp_kind``) are read too.

        Raises
        ------
        ValueError
            Naming the file, if it is not a line trajectory, or its figures or scene do not fit
            its series (:func:`~cable_ocp.simulation.trajectory.check_recorded`).
        """
        path = Path(path).with_suffix(".nc")
        try:
            with xr.open_dataset(path) as root:
                old = netcdf.KIND not in root.attrs and root.attrs.get("cable_ocp_kind") == KIND
            whole = None if old else netcdf.read(path, KIND)  # checked against its groups
            attrs = root.attrs if old else whole.attrs
            names = [f"segment_{k}" for k in range(int(attrs["segments"]))]
            if old:
                datasets = [_old_segment(path, name) for name in names]
            else:  # one open of the file for every segment (100 segments: 33 s -> a few)
                datasets = netcdf.read_groups(path, KIND, names)
            length = float(attrs["element_length"])
            run = cls([Trajectory.from_xarray(dataset) for dataset in datasets], length)
            here = whole is not None and netcdf.written_here(whole)
            check_recorded(run, run.time, run.clearance_error, None, here)
            if whole is not None:
                _check_views(run, whole)
            for k, segment in enumerate(run.segments):
                if not np.array_equal(segment.omega, run.omega, equal_nan=True):
                    raise ValueError(
                        f"segment_{k}: omega = {segment.omega!r} m: expected the run's, "
                        f"{run.omega!r} m in segment_0"
                    )
        except (OSError, KeyError, ValueError, TypeError) as error:
            where = "" if str(path) in str(error) else f"{path}: "
            raise ValueError(f"{where}not a readable line trajectory ({error})") from None
        return run


def _check_views(run: LineTrajectory, whole: xr.Dataset) -> None:
    """ValueError naming the first whole-run view stored at the root that its segments differ from.

    The loader rebuilds the views from the segments; a root that says otherwise was edited.
    """
    for name in ("time", *VIEWS):
        if name in whole.variables:
            stored, own = whole[name].values, getattr(run, name)
            if stored.shape != own.shape or not np.array_equal(stored, own, equal_nan=True):
                raise ValueError(
                    f"{name}: the whole-run view stored at the root is not its segments' "
                    "(an edited file)"
                )


def _cf(units: str, long_name: str) -> dict[str, str]:
    """The CF attributes of a variable of the whole run."""
    return {"units": units, "long_name": long_name}


def _old_segment(path: Path, group: str) -> xr.Dataset:
    """The Dataset of a segment's group of a file written before the result format, as is."""
    with xr.open_dataset(path, group=group) as dataset:
        return dataset.load()
