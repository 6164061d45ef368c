"""Tabulated top motion (cable_ocp.drive.vessel): the natural spline through a table, checks."""

from __future__ import annotations

import numpy as np
import pytest

from cable_ocp.drive import vessel


def good_table(count: int = 6) -> tuple[np.ndarray, np.ndarray]:
    time_ = np.linspace(0.0, 5.0, count)
    return time_, np.column_stack([time_, 0.5 * time_, np.zeros(count)])


def test_tabulated_top_accepts_a_good_table():
    time_, points = good_table()
    position, velocity, acceleration = vessel.tabulated_top(time_, points)(np.array([0.0, 2.5]))
    # A straight line at constant speed: the natural spline reproduces it to rounding.
    np.testing.assert_allclose(position[:, 1], [2.5, 1.25, 0.0], atol=1e-12)
    np.testing.assert_allclose(velocity[:, 1], [1.0, 0.5, 0.0], atol=1e-12)
    np.testing.assert_allclose(acceleration, 0.0, atol=1e-12)


@pytest.mark.parametrize(
    "case",
    ["decreasing t", "repeated t", "nan in t", "nan in x", "inf in z", "3 rows", "2 columns",
     "points rows != times", "2-d times"],
)  # fmt: skip
def test_tabulated_top_rejects_bad_tables(case):
    time_, points = good_table()
    if case == "decreasing t":
        time_ = time_[::-1].copy()
    elif case == "repeated t":
        time_[3] = time_[2]
    elif case == "nan in t":
        time_[2] = np.nan
    elif case == "nan in x":
        points[4, 0] = np.nan
    elif case == "inf in z":
        points[1, 2] = np.inf
    elif case == "3 rows":
        time_, points = time_[:3], points[:3]
    elif case == "2 columns":
        points = points[:, :2]
    elif case == "points rows != times":
        points = points[:-1]
    elif case == "2-d times":
        time_ = time_[:, None]
    with pytest.raises(ValueError, match=r"top\.table"):
        vessel.tabulated_top(time_, points)


def test_tabulated_top_refuses_times_outside_the_table():
    motion = vessel.tabulated_top(*good_table())
    with pytest.raises(ValueError, match=r"top\.table covers"):
        motion(np.array([5.5]))


def test_read_table_with_header(tmp_path):
    path = tmp_path / "vessel.csv"
    path.write_text("t,x,y,z\n0,0,0,0\n1,1.5,0.25,-0.5\n2,3,0.5,-1\n3,4.5,0.75,-1.5\n")
    time_, points = vessel.read_table(path)
    np.testing.assert_array_equal(time_, [0, 1, 2, 3])
    np.testing.assert_array_equal(points[1], [1.5, 0.25, -0.5])
    assert points.shape == (4, 3)
    # Without a header the same numbers come back.
    path.write_text("\n".join(path.read_text().splitlines()[1:]) + "\n")
    np.testing.assert_array_equal(vessel.read_table(path)[1], points)


def test_read_table_rejects_wrong_columns(tmp_path):
    path = tmp_path / "three.csv"
    path.write_text("t,x,y\n0,0,0\n1,1,0\n2,2,0\n3,3,0\n")
    with pytest.raises(ValueError, match=r"top\.table"):
        vessel.read_table(path)
