"""The seabed of eq. 40 and the objective of eq. 39 (cable_ocp.simulation.seabed).

The clearance error is the integrand of eq. 39, with the seabed under the end's start delta below
it.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from cable_ocp.scene.schema import Hill
from cable_ocp.simulation.seabed import clearance_error, rms_objective, seabed_height

HILLS = (Hill(height=15.0, x0=70.0, y0=20.0, width_x=20.0, width_y=20.0),)


@pytest.mark.parametrize("delta", [0.0, 5.0, 12.5])
def test_clearance_error_is_the_paper_integrand(delta):
    """e = clearance over the seabed - delta, the seabed under the start delta below the end."""
    rng = np.random.default_rng(7)
    end = np.column_stack(
        [rng.uniform(0, 140, 50), rng.uniform(-10, 40, 50), rng.uniform(-300, -280, 50)]
    )
    level = end[0, 2] - delta - seabed_height(HILLS, end[0, 0], end[0, 1])  # the flat level
    clearance = end[:, 2] - (level + seabed_height(HILLS, end[:, 0], end[:, 1]))
    assert clearance[0] == pytest.approx(delta, abs=1e-12)
    assert np.allclose(clearance_error(HILLS, end), clearance - delta, atol=1e-12)


def test_an_end_that_follows_the_hill_has_zero_objective():
    """The end starts delta above the seabed and keeps delta above the hill: Omega = 0.

    Also from a start over the hill's flank (x = 40 m, 5.5 m up): e(0) = 0 there.
    """
    t = np.linspace(0.0, 210.0, 2101)
    for x in (t - 100.0, t / 2 + 40.0):  # from flat ground over the hill top; from its flank
        y = np.full(t.shape, 20.0)
        z = -295.0 + seabed_height(HILLS, x, y)
        assert rms_objective(t, clearance_error(HILLS, np.column_stack([x, y, z]))) < 1e-12
    x, y = t - 100.0, np.full(t.shape, 20.0)
    start = -295.0
    z = start + seabed_height(HILLS, x, y)
    error = clearance_error(HILLS, np.column_stack([x, y, z]))
    assert rms_objective(t, error) < 1e-12
    assert rms_objective(t, clearance_error((), np.column_stack([x, y, z]))) > 1.0


# ----------------------------------------------------------------------------------------------
HILL = Hill(height=15.0, x0=70.0, y0=20.0, width_x=20.0, width_y=30.0)
OTHER = Hill(height=-4.0, x0=-10.0, y0=5.0, width_x=8.0, width_y=12.0)


def test_single_hill_matches_eq_40():
    x = np.array([70.0, 90.0, 70.0, 50.0, 90.0, 300.0])
    y = np.array([20.0, 20.0, 50.0, -10.0, -10.0, 20.0])
    expected = [15.0, 15 / np.e, 15 / np.e, 15 * np.exp(-2), 15 * np.exp(-2), 0.0]
    np.testing.assert_allclose(seabed_height([HILL], x, y), expected, rtol=1e-14, atol=1e-14)
    assert seabed_height([HILL], 70.0, 20.0) == 15.0  # scalars in, scalar out
    np.testing.assert_array_equal(seabed_height([], x, y), 0.0)  # flat seabed


def test_seabed_symbolic_matches_numpy():
    x, y = ca.SX.sym("x"), ca.SX.sym("y")
    hills = [HILL, OTHER]
    height = ca.Function("z", [x, y], [seabed_height(hills, x, y)])
    points = np.random.default_rng(3).uniform([-40, -30], [120, 70], size=(25, 2))
    symbolic = np.array(height(points[:, 0], points[:, 1])).ravel()
    np.testing.assert_allclose(symbolic, seabed_height(hills, *points.T), rtol=1e-14, atol=1e-14)
    mx = ca.MX.sym("x")
    assert isinstance(seabed_height(hills, mx, 0.0), ca.MX)


def test_hills_add():
    x, y = np.meshgrid(np.linspace(-50, 150, 21), np.linspace(-40, 80, 13))
    both = seabed_height([HILL, OTHER], x, y)
    np.testing.assert_allclose(
        both, seabed_height([HILL], x, y) + seabed_height([OTHER], x, y), rtol=0, atol=1e-14
    )


def test_clearance_error_follows_the_seabed():
    end = np.array([[0.0, 0.0, -295.0], [70.0, 20.0, -290.0], [300.0, 0.0, -295.5]])
    under_start = 15 * np.exp(-((70 / 20) ** 2) - (20 / 30) ** 2)  # the hill's foot, 4.6e-5 m
    expected = [0.0, 5.0 - 15.0 + under_start, -0.5 + under_start]  # measured from the start
    np.testing.assert_allclose(clearance_error([HILL], end), expected, rtol=1e-12, atol=1e-14)


@pytest.mark.parametrize("c", [0.0, 0.3, -2.5])
def test_rms_of_a_constant(c):
    t = np.linspace(3.0, 13.0, 41)
    # Exact up to rounding (tolerance 1e-14 relative).
    assert rms_objective(t, np.full_like(t, c)) == pytest.approx(abs(c), rel=1e-14, abs=1e-15)


def test_rms_of_a_sine_over_whole_periods():
    t = np.linspace(0.0, 3 * 2 * np.pi, 601)
    # The trapezoidal rule is exact for sin^2 over whole periods on a uniform grid (to 1e-12).
    assert rms_objective(t, np.sin(t)) == pytest.approx(1 / np.sqrt(2), abs=1e-12)
    t = np.linspace(5.0, 25.0, 77)  # 2 periods of 10 s, another start and grid
    assert rms_objective(t, 0.4 * np.sin(2 * np.pi * t / 10)) == pytest.approx(
        0.4 / np.sqrt(2), abs=1e-12
    )
