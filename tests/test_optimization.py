"""Optimal winch control: the optimiser works, respects its bounds and fails loudly."""

from __future__ import annotations

import numpy as np
import pytest

from cable_ocp.controls import HermiteIntervals, KnotSpline
from cable_ocp.nelder_mead import NelderMeadSettings
from cable_ocp.ocp import IpoptSettings, angle_bounds
from cable_ocp.optimization import OcpResult, optimize
from cable_ocp.scene import load_scene
from cable_ocp.simulation import simulate
from cable_ocp.winch import spline_angle

# small_tow: 100 m cable, n = 4, 40 s; the same model for optimisation and verification.
SETTINGS = IpoptSettings(step=0.25, intervals=8)


@pytest.fixture(scope="module")
def small(models_dir):
    return load_scene(models_dir / "small_tow.toml")


@pytest.fixture(scope="module")
def solved(small):
    return optimize(small, "ipopt", SETTINGS, quiet=True), simulate(small)


def test_ipopt_beats_locked_winch(solved, small):
    """Omega of the optimised winch is far below the locked one (measured 2.2e-4 vs 0.58 m)."""
    result, locked = solved
    assert result.success, result.status
    assert locked.omega > 0.3
    assert result.omega < 0.02 * locked.omega
    # Omega is the verified one: it equals a fresh simulation of the scene with that winch.
    control = HermiteIntervals(40.0, SETTINGS.intervals)
    again = simulate(small, winch=control.angle_function(result.parameters))
    assert again.omega == pytest.approx(result.omega, rel=1e-12)


def test_winch_bounds_hold_along_the_trajectory(solved, small):
    result, _ = solved
    low, high = angle_bounds(small, small.segment_length)
    phi = result.trajectory.winch_angle
    assert phi.min() >= low - 1e-9 and phi.max() <= high + 1e-9
    length = result.trajectory.top_length
    assert length.min() >= small.winch.top_length_min - 1e-9
    assert length.max() <= small.winch.top_length_max + 1e-9


def test_result_round_trip(solved, tmp_path):
    result, _ = solved
    result.save(tmp_path / "r")
    back = OcpResult.load(tmp_path / "r")
    assert np.array_equal(back.parameters, result.parameters)
    assert back.trajectory.equals(result.trajectory)
    assert back.omega == result.omega and back.status == result.status


def test_infeasible_bounds_fail_loudly(small):
    """A heave the rate-limited winch cannot compensate within its angle range: IPOPT says so."""
    scene = small.updated(
        {
            "top.heave_amplitude": 6.0,
            "top.heave_period": 10.0,
            "top.heave_compensation": True,
            "winch.rate_max": 0.1,
        }
    )
    result = optimize(scene, "ipopt", SETTINGS, quiet=True)
    assert not result.success
    assert "Infeasible" in result.status


def test_nelder_mead_at_its_evaluation_limit_is_not_a_success(small):
    result = optimize(
        small, "nelder-mead", NelderMeadSettings(step=0.5, max_evaluations=20), quiet=True
    )
    assert not result.success
    assert result.evaluations <= 21
    assert "evaluations" in result.status.lower()


def test_exact_hessian_needs_the_interpreted_model():
    with pytest.raises(ValueError, match="second derivatives"):
        IpoptSettings(hessian="exact", compiled=True)


def test_unknown_method_is_rejected(small):
    with pytest.raises(ValueError, match="method"):
        optimize(small, "gradient-descent")


def test_spline_basis_matches_the_winch_spline():
    control = KnotSpline(210.0, 14)
    values = np.random.default_rng(3).normal(size=14)
    t = np.linspace(0.0, 210.0, 777)
    basis = control.basis(t)
    reference = spline_angle(210.0, values)(t)
    for b, r in zip(basis, reference, strict=True):
        assert np.allclose(b @ values, r, atol=1e-12)


def test_hermite_basis_interpolates_its_nodes():
    control = HermiteIntervals(100.0, 10)
    p = np.random.default_rng(4).normal(size=control.size)
    nodes = np.arange(1, 11) * 10.0
    b0, b1, _ = control.basis(nodes)
    assert np.allclose(b0 @ p, p[:10]) and np.allclose(b1 @ p, p[10:])
    start = control.basis(np.zeros(1))
    assert np.allclose(start[0] @ p, 0.0) and np.allclose(start[1] @ p, 0.0)
