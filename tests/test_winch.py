"""The winch angle (cable_ocp.drive.winch): the spline through the knots and tabulated series."""

from __future__ import annotations

import numpy as np
import pytest

from cable_ocp.drive import winch


def test_spline_angle_through_knots_from_rest():
    duration, values = 210.0, np.array([1.0, -2.0, 3.5, 0.0, 4.0, -1.0, 2.0])
    angle = winch.spline_angle(duration, values)
    knots = winch.knot_times(duration, values.size)
    np.testing.assert_allclose(knots, np.arange(values.size + 1) * duration / values.size)
    phi, rate, acceleration = angle(knots)
    np.testing.assert_allclose(phi, np.concatenate([[0.0], values]), atol=1e-12)
    assert phi[0] == 0.0
    assert abs(rate[0]) < 1e-12
    assert abs(acceleration[-1]) < 1e-12  # free end, phi''(T) = 0
    # The rates are the spline's derivatives (central differences, tolerance 1e-5 relative).
    t, dt = np.array([17.0, 101.3, 188.8]), 1e-4
    numeric = (angle(t + dt)[0] - angle(t - dt)[0]) / (2 * dt)
    np.testing.assert_allclose(angle(t)[1], numeric, rtol=1e-5)


def test_tabulated_angle_interpolates_a_good_series():
    t = np.linspace(0.0, 10.0, 6)
    angle = winch.tabulated_angle(t, 0.3 * t)
    np.testing.assert_allclose(angle(np.array([0.0, 5.0, 7.5]))[0], [0.0, 1.5, 2.25], atol=1e-12)


@pytest.mark.parametrize(
    ("times", "angles"),
    [
        ([0, 1, 2], [0, 1, 2]),  # fewer than 4 samples
        ([0, 1, 2, 3], [0, 1, 2]),  # lengths differ
        ([0, 1, 1, 3], [0, 1, 2, 3]),  # not strictly increasing
        ([0, 2, 1, 3], [0, 1, 2, 3]),  # decreasing
        ([0.5, 1, 2, 3], [0, 1, 2, 3]),  # does not start at 0 s
        ([0, 1, 2, 3], [0.1, 1, 2, 3]),  # phi(0) != 0
        ([0, 1, 2, 3], [0, np.nan, 2, 3]),  # NaN
        ([0, 1, np.inf, 3], [0, 1, 2, 3]),  # inf
    ],
)
def test_tabulated_angle_rejects_bad_series(times, angles):
    with pytest.raises(ValueError, match="winch time series"):
        winch.tabulated_angle(np.array(times, float), np.array(angles, float))


@pytest.mark.parametrize(
    ("function", "message"),
    [
        (lambda t: 1.5, r"returned float 1\.5; a winch function must return \(phi"),
        (lambda t: (0.0 * t, 0.0 * t), r"returned tuple .*; a winch function must return"),
        (lambda t: (0.2, 0.0, 0.0), r"phi has shape \(\) for t of shape \(2,\)"),
        (lambda t: (0.0 * t, np.full_like(t, np.inf), 0.0 * t), r"phi' at t = 0 s is inf"),
        (lambda t: (0.0 * t, 0.0 * t, np.full_like(t, np.nan)), r"phi'' at t = 0 s is nan"),
    ],
    ids=["number", "two values", "scalars", "infinite rate", "NaN acceleration"],
)
def test_a_winch_function_that_returns_no_angle_history_is_refused_naming_the_winch(
    function, message
):
    """Checked once, where every drive takes its angle (issue 45, item 8)."""
    from cable_ocp.drive.drive import Drive
    from cable_ocp.scene.schema import scene_from_dict

    scene = scene_from_dict({"model": {"elements": 4}, "top": {}, "numerics": {}})
    with pytest.raises(ValueError, match=r"^winch: the function") as caught:
        Drive.from_scene(scene, function)
    assert caught.match(message)
    Drive.from_scene(scene, lambda t: (0.0 * t, 0.0 * t, 0.0 * t))  # an angle history passes
