"""One atomic netCDF writer (issue 41): every result and the sweep's store go through
``result_files.netcdf.write``: a scratch file beside the target, flushed to the disk, renamed
onto it, with declared units on every variable of numbers."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from cable_ocp.result_files import netcdf
from cable_ocp.sweep import store
from cable_ocp.sweep.spec import Case


def _record() -> dict:
    time = np.linspace(0.0, 2.0, 5)
    series = {name: np.zeros(5) for name in store.SERIES}
    return {"time": time, **series, "omega": 0.1, "wall_time": 1.5, "status": "ok",
            "reason": "", "success": True}  # fmt: skip


def test_a_case_file_is_written_by_the_one_writer_flushed_then_renamed(tmp_path, monkeypatch):
    events: list[str] = []
    write, fsync, replace = netcdf.write, os.fsync, os.replace
    monkeypatch.setattr(netcdf, "write", lambda *a, **k: events.append("write") or write(*a, **k))
    monkeypatch.setattr(os, "fsync", lambda fd: events.append("fsync") or fsync(fd))
    monkeypatch.setattr(os, "replace", lambda a, b: events.append(f"replace {Path(b).name}")
                        or replace(a, b))  # fmt: skip
    (tmp_path / "cases").mkdir(mode=0o750)
    os.chmod(tmp_path / "cases", 0o750)
    case = Case(index=3, overrides={"numerics.step": 0.1}, scene=None, fingerprint="abc")
    path = store.write_case(tmp_path, case, _record())
    assert events == ["write", "fsync", "replace case_00003.nc"]
    assert sorted(p.name for p in path.parent.iterdir()) == ["case_00003.nc"]  # no scratch
    assert path.stat().st_mode & 0o777 == 0o640  # the folder's permissions, no execute bits
    with xr.open_dataset(path) as data:
        numbers = [n for n, v in data.variables.items() if v.dtype.kind in "iuf"]
        assert {"time", "omega", "wall_time", *store.SERIES} <= set(numbers)
        assert {n: data[n].attrs["units"] for n in numbers} == {n: store.UNITS[n] for n in numbers}
    assert float(store.read_case(path)["omega"]) == 0.1


def test_a_failed_write_leaves_the_old_file_and_no_scratch(tmp_path, monkeypatch):
    case = Case(index=0, overrides={}, scene=None, fingerprint="abc")
    path = store.write_case(tmp_path, case, _record())
    before = path.read_bytes()

    def interrupted(fd):
        raise KeyboardInterrupt

    monkeypatch.setattr(os, "fsync", interrupted)
    with pytest.raises(KeyboardInterrupt):
        store.write_case(tmp_path, case, {**_record(), "omega": 0.2})
    assert path.read_bytes() == before
    assert [p.name for p in path.parent.iterdir()] == ["case_00000.nc"]


def test_a_variable_of_numbers_without_units_is_refused_before_writing(tmp_path):
    data = xr.Dataset({"depth": ("time", [1.0, 2.0]), "note": ((), "text"), "ok": ((), True)})
    with pytest.raises(ValueError, match=r"group\.nc: segment_0/depth has no declared units"):
        netcdf.write(xr.Dataset(), tmp_path / "group.nc", {"segment_0": data})
    assert list(tmp_path.iterdir()) == []
    data["depth"].attrs["units"] = "m"
    assert netcdf.write(data, tmp_path / "fine.nc").is_file()


def test_a_result_saved_into_a_new_folder_makes_it(tmp_path):
    """Trajectory.save(path) in a folder not made yet (netCDF said "Permission denied")."""
    data = xr.Dataset({"depth": ("time", [1.0, 2.0], {"units": "m"})})
    path = netcdf.write(data, tmp_path / "new" / "deeper" / "run.nc")
    assert path.is_file() and [p.name for p in path.parent.iterdir()] == ["run.nc"]
