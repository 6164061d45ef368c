"""Winch bounds hold everywhere in time, within BOUND_TOLERANCE; a broken bound or a failed
verification is a failed result, never an exception or a success."""

from __future__ import annotations

import numpy as np
import pytest

from cable_ocp.control import verification as verification_module
from cable_ocp.control.nelder_mead import NelderMeadSettings
from cable_ocp.control.optimization import optimize
from cable_ocp.control.settings import GridSettings, ModelSettings
from cable_ocp.drive.bounds import (
    BOUND_TOLERANCE,
    HEAVE_SAMPLES,
    LinearBounds,
    angle_bounds,
    bernstein_rows,
    subintervals,
    violation,
)
from cable_ocp.drive.controls import HermiteIntervals, KnotSpline
from cable_ocp.drive.drive import Drive
from cable_ocp.scene.schema import load_scene
from cable_ocp.simulation.integrate import SimulationError
from cable_ocp.simulation.run import check_top_length

# small_tow cut to 20 s at h = 0.5 s, so that each IPOPT solve is short.
SHORT = {"numerics.duration": 20.0, "numerics.step": 0.5}
FINE = np.linspace(0.0, 20.0, 200_001)  # 0.1 ms apart


@pytest.fixture(scope="module")
def short(models_dir):
    return load_scene(models_dir / "small_tow.toml").updated(SHORT)


def test_bernstein_constraints_bound_the_control_everywhere():
    """Random controls: the constraint rows bound angle, rate and acceleration on a fine grid."""
    rng = np.random.default_rng(5)
    t = np.linspace(0.0, 40.0, 400_001)
    grid = np.arange(81) * 0.5
    for control in (HermiteIntervals(40.0, 8), KnotSpline(40.0, 4)):
        p = rng.normal(size=control.size)
        for derivative in range(3):
            rows = bernstein_rows(control, *subintervals(control, grid), derivative) @ p
            values = control.basis(t)[derivative] @ p
            assert rows.min() <= values.min() + 1e-12 and values.max() <= rows.max() + 1e-12
            # ... and tightly: conservative by far less than the range on 0.5 s sub-intervals.
            assert rows.max() - values.max() < 0.01 * np.ptp(values)


def test_a_profile_evaluates_as_its_basis_rows_on_every_control():
    """The bound checks evaluate the profile (``angle_function``), not its basis rows: the same
    angle, rate and acceleration, breakpoints included, on each control."""
    from cable_ocp.control.hermite_nodes import HermiteNodes

    rng = np.random.default_rng(7)
    nodes = HermiteNodes(np.array([0.0, 3.5, 10.0, 12.0, 25.0, 40.0]))
    for control in (HermiteIntervals(40.0, 8), nodes, KnotSpline(40.0, 4)):
        p = rng.normal(size=control.size)
        t = np.concatenate([np.linspace(0.0, 40.0, 1001), control.breakpoints])
        evaluated = control.angle_function(p)(t)
        for derivative in range(3):
            rows = control.basis(t)[derivative] @ p
            np.testing.assert_allclose(evaluated[derivative], rows, rtol=0, atol=1e-11)


def test_bounds_carried_onto_a_control_on_the_same_sub_intervals_are_built_ones(short):
    """``on_control`` (the adaptive grid's candidates) keeps the limits, heave compensation
    included, where the sub-intervals are the same, and builds anew where they are not: both
    equal to :meth:`LinearBounds.build` on the new control, to the bit."""
    from cable_ocp.control.hermite_nodes import HermiteNodes

    scene = short.updated(
        {
            "top.heave.sea_state.significant_height": 0.5,
            "top.heave.sea_state.peak_period": 7.0,
            "top.heave.compensation": True,
            "winch.rate_max": 1.0,
            "winch.acceleration_max": 0.5,
        }
    )
    grid = np.arange(41) * 0.5
    bounds = LinearBounds.build(scene, HermiteIntervals(20.0, 4), grid)
    angle_rows = bounds.derivatives == 0
    assert np.ptp(bounds.lower[angle_rows]) > 1e-3  # the heave's extremes are in the limits
    on_grid = HermiteNodes(np.arange(9) * 2.5)  # nodes on RK4 step ends: the same sub-intervals
    off_grid = HermiteNodes(np.array([0.0, 2.25, 20.0]))  # a node between them
    for control in (on_grid, off_grid):
        carried, built = (
            bounds.on_control(scene, control, grid),
            LinearBounds.build(scene, control, grid),
        )
        for field in ("matrix", "lower", "upper", "derivatives", "starts"):
            np.testing.assert_array_equal(getattr(carried, field), getattr(built, field))
    assert bounds.on_control(scene, off_grid, grid).matrix.shape[0] > bounds.matrix.shape[0]


def test_a_dip_between_samples_is_caught(short):
    """A Hermite profile within the bound at every 0.5 s sample but 3e-4 rad above it between."""
    scene = short.updated({"winch.angle_max": 0.5168})
    control = HermiteIntervals(20.0, 2)
    p = np.array([0.49, 0.0, 0.05, 0.0])
    grid = np.arange(41) * 0.5
    phi = control.angle_function(p)
    assert phi(grid)[0].max() <= 0.5168  # the samples keep the bound ...
    assert phi(FINE)[0].max() > 0.5168 + 2e-4  # ... the profile does not
    reason = violation(scene, control, p)
    assert reason is not None and "winch angle" in reason and "winch.angle_min/max" in reason
    assert LinearBounds.build(scene, control, grid).excess(p) > 2e-4


def test_the_angle_rows_hold_the_heave_between_its_samples(short):
    """Heave compensation on 5 s sub-intervals (17 samples 0.31 s apart, a 7 s sea): each angle
    row leaves room for the heave part's true extremes on its sub-interval (on a 1 ms grid),
    which the samples alone miss (whole-space seed 2 case 2's drum passed its bound between
    them)."""
    scene = short.updated(
        {
            "top.heave.sea_state.significant_height": 2.0,
            "top.heave.sea_state.peak_period": 7.0,
            "top.heave.compensation": True,
        }
    )
    grid = np.arange(5) * 5.0
    bounds = LinearBounds.build(scene, HermiteIntervals(20.0, 4), grid)
    low, high = bounds.lower[bounds.derivatives == 0], bounds.upper[bounds.derivatives == 0]
    starts = bounds.starts[bounds.derivatives == 0]
    lowest, highest = angle_bounds(scene)
    missed = 0.0
    for start in np.unique(starts):
        on = starts == start
        dense = start + np.linspace(0.0, 5.0, 5001)
        heave = Drive.from_scene(scene).winch_angle(dense)[0]
        samples = heave[:: 5000 // (HEAVE_SAMPLES - 1)]
        assert np.all(high[on] + heave.max() <= highest) and np.all(low[on] + heave.min() >= lowest)
        missed = max(missed, heave.max() - samples.max(), samples.min() - heave.min())
    assert missed > 1e-4  # the samples alone miss the heave's extremes by this much


def test_top_length_check_accepts_the_tolerance(short):
    """simulate's length check: r_D * BOUND_TOLERANCE outside passes, ten times that raises."""
    times = np.array([0.0, 1.0])
    radius = short.winch.drum_radius
    edge = (short.winch.top_length_max - short.top_element_length) / radius  # 35 rad

    def drive(angle):
        return Drive.from_scene(short, lambda t: (np.full(t.shape, angle), 0 * t, 0 * t))

    check_top_length(short, drive(edge + 0.5 * BOUND_TOLERANCE), times)
    with pytest.raises(ValueError, match="top_length_max.*tolerance"):
        check_top_length(short, drive(edge + 10 * BOUND_TOLERANCE), times)


@pytest.fixture(scope="module")
def on_the_bound(short):
    """IPOPT on a scene whose angle bound (0.5 rad) is too tight for the winch it wants (~1 rad)."""
    scene = short.updated({"winch.angle_max": 0.5, "winch.rate_max": 0.05})
    settings = GridSettings(intervals=4)
    return scene, settings, optimize(scene, grid=settings, quiet=True)


def test_ipopt_on_the_angle_bound_returns_a_result_within_tolerance(on_the_bound):
    """IPOPT stops on the angle bound (within 1e-4 rad of it) and within the bound tolerances."""
    scene, settings, result = on_the_bound
    assert result.success, result.status
    control = HermiteIntervals(20.0, settings.intervals)
    phi, rate, _ = control.angle_function(result.parameters)(FINE)
    assert phi.max() > 0.5 - 1e-4  # the bound is active
    assert phi.max() <= 0.5 + BOUND_TOLERANCE
    assert np.abs(rate).max() <= 0.05 + BOUND_TOLERANCE
    assert result.trajectory.top_length.max() <= scene.winch.top_length_max
    assert violation(scene, control, result.parameters) is None


def test_nelder_mead_respects_the_rate_bound(models_dir):
    """small_tow with rate_max = 0.05 rad/s: |phi'| on a fine grid stays within it.

    Omega must stay below half the locked winch's (0.58 m).
    """
    scene = load_scene(models_dir / "small_tow.toml").updated({"winch.rate_max": 0.05})
    result = optimize(
        scene,
        "nelder-mead",
        NelderMeadSettings(max_evaluations=600),
        model=ModelSettings(step=0.5),
        quiet=True,
    )
    rate = KnotSpline(40.0, scene.winch.knots).angle_function(result.parameters)(
        np.linspace(0.0, 40.0, 400_001)
    )[1]
    assert np.abs(rate).max() <= 0.05 + BOUND_TOLERANCE
    assert result.success, result.status
    assert result.omega < 0.5 * 0.58


def test_nelder_mead_starts_within_a_tight_rate_bound(short):
    """The first guess is scaled into the bounds: even 20 evaluations return a feasible profile."""
    scene = short.updated({"winch.rate_max": 0.001})
    result = optimize(scene, "nelder-mead", NelderMeadSettings(max_evaluations=20), quiet=True)
    rate = KnotSpline(20.0, scene.winch.knots).angle_function(result.parameters)(FINE)[1]
    assert np.abs(rate).max() <= 0.001 + BOUND_TOLERANCE
    assert not result.success and "evaluations" in result.status


def test_verification_failure_is_a_failed_result(short, monkeypatch):
    def broken(*args, **kwargs):
        raise SimulationError("the bonds tore at t = 3 s")

    monkeypatch.setattr(verification_module, "simulate", broken)
    result = optimize(short, grid=GridSettings(intervals=2), quiet=True)
    assert not result.success
    assert "; verification failed: no trustworthy simulation of the full model" in result.status
    assert result.status.startswith("Gauss-Newton converged")
    assert "at h = 0.125 s" in result.status and "bonds tore" in result.status
    assert result.trajectory is None and np.isnan(result.omega)
    assert result.parameters.size == 4


def test_nelder_mead_verification_failure_is_a_failed_result(short, monkeypatch):
    def broken(*args, **kwargs):
        raise ValueError("top element too long")

    monkeypatch.setattr(verification_module, "simulate", broken)
    result = optimize(short, "nelder-mead", NelderMeadSettings(max_evaluations=400), quiet=True)
    assert not result.success
    assert result.status == (  # the same wording as the shooting solvers' (one verified loop)
        "Nelder-Mead converged (Optimization terminated successfully.); verification failed: "
        "the full-model simulation raised ValueError: top element too long"
    )
