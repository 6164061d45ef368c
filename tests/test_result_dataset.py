"""Results as labelled Datasets (cable_ocp.result_files): any dataclass field, by its type."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np
import pytest
import xarray as xr

from cable_ocp.result_files import dataset, netcdf, units


@dataclass(frozen=True, eq=False)
class Toy:
    """A result with a field of every kind.

    Attributes
    ----------
    speed : array (k,), m/s^2
        How fast it goes. Further text.
    count : int
    flag : bool
    name : str
    history : list of float, m^2
    span : (float, float), rad
    series : dict of str to array (k,)
    scores : dict of str to float
    settings : dict
    """

    UNITS: ClassVar[dict[str, str]] = {
        "speed": "m s-2", "count": "1", "flag": "1", "history": "m2", "span": "rad",
        "series": "m", "scores": "1", "added": "s",
    }  # fmt: skip

    speed: np.ndarray
    count: int
    flag: bool
    name: str
    history: list[float]
    span: tuple[float, float]
    series: dict[str, np.ndarray]
    scores: dict[str, float]
    settings: dict
    added: float = float("nan")  # a field not documented, with a default
    notes: list[str] = field(default_factory=list)


def _toy() -> Toy:
    return Toy(np.arange(3.0), 4, True, "x", [1.0, float("nan")], (-1.0, 2.0),
               {"a": np.ones(3)}, {"a": 0.5}, {"h": 1, "on": None})  # fmt: skip


def test_every_kind_of_field_goes_through_netcdf(tmp_path):
    toy = _toy()
    dims = {"speed": ("time",), "series": ("key", "time"), "scores": ("key",)}
    path = netcdf.write(dataset.to_dataset(toy, "Toy", dims), tmp_path / "toy.nc")
    back = Toy(**dataset.from_dataset(Toy, netcdf.read(path, "Toy")))
    assert dataset.fields_equal(back, toy)
    with xr.open_dataset(path) as data:
        assert all(v.attrs.get("units") for v in data.variables.values())
        assert data["speed"].attrs == {"units": "m s-2", "long_name": "How fast it goes"}
        assert data["history"].attrs["units"] == "m2" and data["span"].attrs["units"] == "rad"
        assert data["added"].attrs == {"units": "s", "long_name": "added"}  # not documented
        assert data.attrs["name"] == "x" and data.attrs["cable_ocp_result"] == "Toy"
    with pytest.raises(ValueError, match="holds a Toy, not a Trajectory"):
        netcdf.read(path, "Trajectory")
    empty = Toy(np.zeros(0), 0, False, "", [], (0.0, 0.0), {}, {}, {})
    path = netcdf.write(dataset.to_dataset(empty, "Toy", dims), tmp_path / "empty.nc")
    again = Toy(**dataset.from_dataset(Toy, netcdf.read(path, "Toy")))
    assert dataset.fields_equal(again, empty)


def test_a_field_the_file_lacks_takes_its_default(tmp_path):
    data = dataset.to_dataset(_toy(), "Toy", {}).drop_vars("added")
    assert np.isnan(dataset.from_dataset(Toy, data)["added"])
    with pytest.raises(ValueError, match=r"missing field\(s\) count"):
        dataset.from_dataset(Toy, data.drop_vars("count"))


@pytest.mark.parametrize(("unit", "cf"), [("m/s", "m s-1"), ("m^2", "m2"), ("rad/s", "rad s-1"),
                                          ("N", "N"), ("s^2", "s2"), ("1/s", "s-1"),
                                          ("%", "percent"), ("1", "1"),
                                          ("N m", "N m")])  # fmt: skip
def test_units_in_the_cf_spelling(unit, cf):
    assert units.UNIT.match(unit) and units.cf_units(unit) == cf


@pytest.mark.parametrize("text", ["metres", "m per step", "kN", "1 m", "bytes", "rad or m"])
def test_what_is_not_a_unit_is_not_taken_for_one(text):
    assert not units.UNIT.match(text)


@dataclass(frozen=True)
class Undeclared:
    """A result that declares units, but not for every field it stores.

    Attributes
    ----------
    depth : float, m
    rate : float, m/s
    """

    UNITS: ClassVar[dict[str, str]] = {"depth": "m"}

    depth: float
    rate: float


@dataclass(frozen=True)
class Documented:
    """A result whose units are only in its docstring: not written (units are declared).

    Attributes
    ----------
    depth : float, m
        Depth below the surface.
    steps : int
    rate : float, metres a second
    """

    depth: float
    steps: int
    rate: float = 0.0


def test_an_undeclared_unit_is_an_error_at_write_time(tmp_path):
    """Not a silent "1" (issue 41): the field, and the remedy, are named; nothing is written."""
    with pytest.raises(ValueError, match=r"Undeclared\.rate: no declared unit \(add it to Undec"):
        dataset.to_dataset(Undeclared(1.0, 2.0), "Undeclared", {})
    with pytest.raises(ValueError, match=r"^Documented declares no UNITS: a result class names"):
        dataset.to_dataset(Documented(1.0, 2), "Documented", {})
    with pytest.raises(ValueError, match=r"Documented\.rate : float, metres a second: 'metres a"):
        units.docstring_units(Documented)
    bare = xr.Dataset({"depth": ((), 3.0)}, attrs=netcdf.file_attributes("Bare"))
    with pytest.raises(ValueError, match=r"bare\.nc: depth has no declared units"):
        netcdf.write(bare, tmp_path / "bare.nc")
    assert list(tmp_path.iterdir()) == []


def test_units_stated_in_a_docstring_are_read_strictly():
    @dataclass(frozen=True)
    class Stated:
        """A result whose units are in its docstring.

        Attributes
        ----------
        depth : float, m
            Depth below the surface.
        steps : int
        """

        depth: float
        steps: int

    assert units.docstring_units(Stated) == {"depth": "m", "steps": "1"}
    assert units.long_names(Stated)["depth"] == "Depth below the surface"


def test_declared_units_agree_with_the_docstrings():
    """A class that declares its units and also states them in its docstring says the same."""
    from cable_ocp.control.closed_loop.result import MpcResult, SolveLog
    from cable_ocp.control.optimization import OcpResult
    from cable_ocp.lowering.checks import LandingReport
    from cable_ocp.lowering.descent import ReferenceDescent
    from cable_ocp.lowering.hold import HoldResult
    from cable_ocp.lowering.landing import LandingResult
    from cable_ocp.lowering.plan import HoldCorrection, LandingPlan
    from cable_ocp.simulation.trajectory import Trajectory

    results = (Trajectory, Toy, OcpResult, MpcResult, SolveLog, LandingPlan, HoldCorrection,
               LandingReport, ReferenceDescent, LandingResult, HoldResult)  # fmt: skip
    for cls in results:
        declared, stated = units.field_units(cls), units.docstring_units(cls)
        shared = [name for name in stated if name in declared and stated[name] != "1"]
        assert len(shared) >= 1, cls.__name__
        assert {n: stated[n] for n in shared} == {n: declared[n] for n in shared}, cls.__name__
