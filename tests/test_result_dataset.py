"""Results as labelled Datasets (cable_ocp.result_files): any dataclass field, by its type."""

from __future__ import annotations

from dataclasses import dataclass, field

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
        assert data["added"].attrs["long_name"] == "added"  # undocumented: its name, units 1
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
                                          ("N", "N"), ("s^2", "s2")])  # fmt: skip
def test_units_in_the_cf_spelling(unit, cf):
    assert units.cf_units(unit) == cf
