"""The Gauss-Newton solver's derivatives against independent references, and its optimum."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import expm

from cable_ocp.control.linearisation import (
    ErrorLinearisation,
    propagate_sensitivities,
    winch_map,
)
from cable_ocp.control.problem import WinchProblem
from cable_ocp.drive.controls import HermiteIntervals
from cable_ocp.drive.drive import stage_times
from cable_ocp.scene.schema import load_scene


@pytest.fixture(scope="module")
def problem(models_dir):
    """paper_hill's first 30 s on a 2-element model at h = 0.5 s, a 6-interval Hermite winch."""
    scene = load_scene(models_dir / "paper_hill.toml", {"numerics.duration": 30.0})
    return WinchProblem.from_scene(scene, HermiteIntervals(30.0, 6), elements=2, step=0.5)


def _linearisation(problem, control):
    """The error's linearisation of ``problem`` (its model, step and grid) under ``control``."""
    times, left = stage_times(problem.grid[:-1], problem.step)
    return ErrorLinearisation(
        problem.model, problem.step, problem.grid.size - 1, control,
        problem.scene.winch.drum_radius, problem.scene.seabed, times, left,
    )  # fmt: skip


@pytest.fixture(scope="module")
def linearisation(problem):
    return _linearisation(problem, problem.control)


def test_sensitivities_of_a_linear_system_follow_its_rk4_step():
    """x' = A x + B w with w = M p at every stage: RK4's step matrix is the 4th-order Taylor
    polynomial T of exp(hA), and a constant input enters by h (I + hA/2 + (hA)^2/6 + (hA)^3/24) B,
    so S_1 = h (...) B M and S_2 = (T + I) S_1."""
    rng = np.random.default_rng(3)
    nx, h, steps, size = 6, 0.1, 2, 4
    a, b = rng.normal(size=(nx, nx)), rng.normal(size=(nx, 3))
    transposed = np.tile(np.hstack([a, b]).T[None, None], (steps, 4, 1, 1))
    inputs = rng.normal(size=(3, size))  # the winch rows of every stage column
    winch = np.tile(np.vstack([inputs] * 3)[None], (steps, 1, 1))
    sensitivities = propagate_sensitivities(transposed, winch, h)
    ha = h * a
    taylor = sum(np.linalg.matrix_power(ha, k) / np.prod(np.arange(1, k + 1)) for k in range(5))
    assert np.max(np.abs(taylor - expm(ha))) < 1e-4  # RK4 is 4th order
    first = h * (np.eye(nx) + ha / 2 + ha @ ha / 6 + ha @ ha @ ha / 24) @ b @ inputs
    assert np.all(sensitivities[0] == 0.0)
    np.testing.assert_allclose(sensitivities[1].T, first, atol=1e-13)
    np.testing.assert_allclose(sensitivities[2].T, (taylor + np.eye(nx)) @ first, atol=1e-13)


def test_sensitivities_of_stages_given_apart_equal_those_of_the_stacked_stages():
    """The step ends' form (four arrays, the middle two one array, as ErrorLinearisation's
    "ends" sweep passes them) gives the same numbers, bit for bit, as the (K, 4, ...) array."""
    rng = np.random.default_rng(5)
    nx, h, steps = 8, 0.1, 30
    control = HermiteIntervals(steps * h, 5, free_start=True)
    times, left = stage_times(np.arange(steps) * h, h)
    winch = winch_map(control, times, left, 0.7)
    points = rng.normal(size=(steps + 1, nx + 3, nx))
    mean = (points[:-1] + points[1:]) * 0.5
    stacked = np.stack([points[:-1], mean, mean, points[1:]], axis=1)
    apart = propagate_sensitivities((points[:-1], mean, mean, points[1:]), winch, h, kept=3)
    assert np.array_equal(apart, propagate_sensitivities(stacked, winch, h, kept=3))


def test_error_and_its_jacobian_match_the_simulation_and_central_differences(
    problem, linearisation
):
    """The error equals the interpreted simulation's (another code path) to 1e-10 m, and the
    Jacobian times a direction equals central differences of that simulation to 1e-7 relative
    (measured 4e-10 m against 1.5e-3 m on paper_hill's whole run)."""
    rng = np.random.default_rng(0)
    parameters = 0.3 * rng.normal(size=problem.control.size)
    values = problem.parameter_values()
    linear = linearisation(values, parameters)
    assert linear.finite
    error = problem.clearance(problem.simulate(parameters))
    np.testing.assert_allclose(linear.error, error, atol=1e-10)
    direction = rng.normal(size=parameters.size)
    eps = 1e-4
    plus = problem.clearance(problem.simulate(parameters + eps * direction))
    minus = problem.clearance(problem.simulate(parameters - eps * direction))
    difference = (plus - minus) / (2 * eps)
    scale = np.max(np.abs(difference))
    assert scale > 1e-4
    np.testing.assert_allclose(linear.jacobian @ direction, difference, atol=1e-7 * scale + 1e-12)
    assert np.all(linear.jacobian[0] == 0.0)  # the start does not depend on the winch


def test_a_blown_up_run_is_reported_not_differentiated(problem, linearisation):
    """A state that becomes non-finite comes back as finite = False (the caller backs off)."""
    values = problem.parameter_values()
    wild = np.full(problem.control.size, 1e6)
    assert not linearisation(values, wild).finite


@pytest.fixture(scope="module")
def held_scene(models_dir):
    """paper_hill's first 60 s with a minimum clearance 0.1 mm under the target clearance: the
    free optimum dips 0.05 mm under the target, so the constraint is active."""
    scene = load_scene(models_dir / "paper_hill.toml", {"numerics.duration": 60.0})
    return scene.updated({"seabed.minimum_clearance": scene.seabed.clearance - 1e-4})


def _minimum_clearance_solve(scene, solver: str):
    from cable_ocp.control.optimization import optimize
    from cable_ocp.control.settings import GridSettings

    return optimize(scene, solver, grid=GridSettings(intervals=12), quiet=True)


def test_the_minimum_clearance_holds_on_the_verified_run(held_scene):
    """Checked on the full model's run (the verification), not on the optimiser's model; the
    model correction learns from a first profile that broke it on the full model."""
    result = _minimum_clearance_solve(held_scene, "gauss-newton")
    assert result.success, result.status
    c_min = held_scene.seabed.minimum_clearance
    assert result.minimum_clearance >= c_min - 1e-3
    clearance = held_scene.seabed.clearance + result.trajectory.clearance_error
    assert clearance.min() >= c_min - 1e-3
    assert result.minimum_clearance == pytest.approx(clearance.min(), abs=1e-12)


@pytest.mark.slow
def test_gauss_newton_and_ipopt_agree_on_the_held_optimum(held_scene):
    """Two solvers of the one transcription, the path constraint included: the same verified
    Omega within 0.1 % (measured 3.97753e-3 m and 3.97760e-3 m)."""
    gauss_newton = _minimum_clearance_solve(held_scene, "gauss-newton")
    ipopt = _minimum_clearance_solve(held_scene, "ipopt")
    assert gauss_newton.success and ipopt.success, (gauss_newton.status, ipopt.status)
    assert gauss_newton.omega == pytest.approx(ipopt.omega, rel=1e-3)


def _solver(problem, **settings):
    from cable_ocp.control.gauss_newton import GaussNewton, GaussNewtonSettings

    return GaussNewton(problem, GaussNewtonSettings(**settings))


def test_the_screened_qp_solves_the_whole_qp(problem, linearisation, monkeypatch):
    """With the angle range narrowed around the guess, so that many Bernstein rows are active,
    the QP on the screened rows gives the whole QP's step (to DAQP's 1e-9)."""
    from cable_ocp.control import gauss_newton

    values = problem.parameter_values()
    parameters = 0.3 * np.random.default_rng(1).normal(size=problem.control.size)
    linear = linearisation(values, parameters)
    rows = problem.bounds.matrix @ parameters
    lower, upper = rows - 0.2, rows + 0.05  # the step wants more than 0.05 rad in places
    screened = _solver(problem).step(linear, parameters, lower, upper, {})
    monkeypatch.setattr(gauss_newton, "SCREENED_ROWS", (0,))  # a QP of no rows: the whole QP
    whole = _solver(problem).step(linear, parameters, lower, upper, {})
    assert screened[2] == whole[2] == "solved"
    active = np.sum(problem.bounds.matrix @ (parameters + whole[0]) > upper - 1e-4)
    assert active >= 3  # the bounds do bind
    np.testing.assert_allclose(screened[0], whole[0], atol=1e-9)
    assert screened[1] == pytest.approx(whole[1], rel=1e-9)


def test_broken_rows_thinned_to_fit_small_qps_still_give_the_whole_qp(
    problem, linearisation, monkeypatch
):
    """Where a step breaks more rows than its screened QP holds, the worst of each run of
    broken rows is added and the QP goes on to a larger one: with screened QPs of 4, 8 and half
    the rows, the rounds thin and end on the whole QP's step (to the QP's margin) without
    solving the whole QP."""
    from cable_ocp.control import gauss_newton

    values = problem.parameter_values()
    parameters = 0.3 * np.random.default_rng(1).normal(size=problem.control.size)
    linear = linearisation(values, parameters)
    rows = problem.bounds.matrix @ parameters
    lower, upper = rows - 0.2, rows + 0.05  # no row near its limit, many broken by the step
    monkeypatch.setattr(gauss_newton, "SCREENED_ROWS", (0,))
    whole = _solver(problem).step(linear, parameters, lower, upper, {})
    count = problem.bounds.matrix.shape[0]
    monkeypatch.setattr(gauss_newton, "SCREENED_ROWS", (4, 8, count // 2))
    thinned, widths = [], []
    worst_nearby, dense_qp = gauss_newton._worst_nearby, gauss_newton._dense_qp
    monkeypatch.setattr(
        gauss_newton, "_worst_nearby", lambda excess: thinned.append(1) or worst_nearby(excess)
    )
    monkeypatch.setattr(
        gauss_newton, "_dense_qp", lambda *args: widths.append(args[2]) or dense_qp(*args)
    )
    screened = _solver(problem).step(linear, parameters, lower, upper, {})
    assert screened[2] == whole[2] == "solved"
    assert thinned and max(widths) == count // 2 < count
    # Other active rows than the whole QP's, held to DAQP's tolerance inside the QP's margin:
    # the steps agree to that margin (4.1e-5 rad measured) and both hold the bounds.
    np.testing.assert_allclose(screened[0], whole[0], atol=gauss_newton.QP_MARGIN)
    assert screened[1] == pytest.approx(whole[1], rel=1e-4)
    assert problem.bounds.excess(parameters + screened[0], lower, upper) == 0.0


def test_a_guess_far_outside_is_brought_inside_by_the_whole_qp_beside_clearance_rows(
    problem, monkeypatch
):
    """With a minimum clearance the whole QP also holds the clearance rows; the nearest feasible
    point of a guess on the bounds' rows alone fills them with rows that always hold (it raised
    on the mismatch once more rows than the screened QPs hold were near their limits)."""
    from cable_ocp.control import gauss_newton

    scene = problem.scene.updated({"seabed.minimum_clearance": 3.0})
    held = WinchProblem.from_scene(scene, HermiteIntervals(30.0, 6), elements=2, step=0.5)
    monkeypatch.setattr(gauss_newton, "SCREENED_ROWS", (0,))  # straight to the whole QP
    solver = _solver(held)
    guess = np.full(held.control.size, 50.0)  # rad and rad/s: far beyond every bound
    inside = solver.feasible(guess, held.bounds.lower, held.bounds.upper, {})
    whole = max(solver._qps)  # built at its first use, here
    assert solver._qps[whole].size1_in(3) == whole > held.bounds.matrix.shape[0]  # clearance rows
    assert held.bounds.excess(guess) > 10 and held.bounds.excess(inside) < 1e-5


def test_a_qp_solution_just_outside_its_rows_is_not_moved_again(problem):
    """A point up to half the QP margin inside the winch bounds counts as inside (DAQP leaves
    its rows by up to 1.6e-5 rad; moving such a point again cost the adaptive grid's carried
    Jacobian, a sensitivity sweep); a point nearer the bounds is brought back inside the QP's
    margin."""
    from cable_ocp.control.gauss_newton import QP_MARGIN
    from cable_ocp.drive.bounds import shrunk

    solver, bounds = _solver(problem), problem.bounds
    live = np.max(np.abs(bounds.matrix), axis=1) > 1e-6  # the rows the parameters move
    # Bounds that put the origin at the given depth under every live row's upper bound (rad).
    for depth, kept in ((0.6 * QP_MARGIN, True), (0.4 * QP_MARGIN, False)):
        lower, upper = np.full(live.size, -1.0), np.where(live, depth, 1.0)
        guess = np.zeros(problem.control.size)
        moved = solver.feasible(guess, lower, upper, {})
        assert (moved is guess) == kept
        held_lower, held_upper = shrunk(lower, upper, QP_MARGIN)
        if not kept:  # the guess was QP_MARGIN - depth over the QP's rows: now a tenth of it
            over = np.max(bounds.matrix @ moved - held_upper)
            assert over < 0.1 * (QP_MARGIN - depth)


def test_linearisations_of_one_shape_share_their_sweep_arrays_and_not_their_results(problem):
    """Two linearisations of one model and horizon (two controls) share one set of work arrays
    (:mod:`cable_ocp.control.sweep_scratch`); interleaved, each returns what it returns alone,
    bit for bit."""
    coarse, fine = (_linearisation(problem, HermiteIntervals(30.0, n)) for n in (3, 6))
    assert coarse._scratch is fine._scratch
    values = problem.parameter_values()
    rng = np.random.default_rng(3)
    on_coarse, on_fine = (0.2 * rng.normal(size=n) for n in (coarse.winch.shape[2], 12))
    alone = coarse(values, on_coarse)
    fine(values, on_fine)
    again = coarse(values, on_coarse)
    np.testing.assert_array_equal(again.jacobian, alone.jacobian)
    np.testing.assert_array_equal(again.states, alone.states)
    assert not np.shares_memory(again.states, alone.states)


def test_keeping_a_jacobian_that_predicts_the_error_finds_the_same_optimum(problem, monkeypatch):
    """The simplified Newton steps (the Jacobian kept while it predicts the error within 5 %)
    reach the optimum of a fresh Jacobian at every iterate: Omega within 1e-6 relative, the
    winch within 1e-6 rad, with fewer simulations with sensitivities."""
    from cable_ocp.control import gauss_newton
    from cable_ocp.control.linearisation import ErrorLinearisation

    calls = []
    original = ErrorLinearisation.__call__

    def counted(self, values, parameters):
        calls.append(1)
        return original(self, values, parameters)

    monkeypatch.setattr(ErrorLinearisation, "__call__", counted)
    values = problem.parameter_values()
    guess = np.zeros(problem.control.size)
    kept = _solver(problem).solve(values, guess)
    kept_calls = len(calls)
    monkeypatch.setattr(gauss_newton, "STALE_JACOBIAN", -1.0)  # never kept
    fresh = _solver(problem).solve(values, guess)
    assert kept.success and fresh.success, (kept.status, fresh.status)
    assert kept.omega == pytest.approx(fresh.omega, rel=1e-6)
    np.testing.assert_allclose(kept.parameters, fresh.parameters, atol=1e-6)
    assert kept_calls < len(calls) - kept_calls


def test_sensitivities_from_the_step_ends_stay_close_to_the_exact_ones(problem):
    """The real-time iteration's Jacobians at the step ends only (the middle stages their mean):
    the same error as the exact sweep's (one model), and a Jacobian within 1e-5 of the exact
    one's norm that comes closer as the step shrinks (measured 1.3e-6 at h = 0.5 s, 4.7e-7 at
    0.25 s)."""
    rng = np.random.default_rng(0)
    parameters = 0.3 * rng.normal(size=problem.control.size)
    gaps = []
    for step in (0.5, 0.25):
        steps = round(30.0 / step)
        grid = np.linspace(0.0, 30.0, steps + 1)
        times, left = stage_times(grid[:-1], step)
        pair = [
            ErrorLinearisation(
                problem.model, step, steps, problem.control, problem.scene.winch.drum_radius,
                problem.scene.seabed, times, left, where,
            )
            for where in ("every", "ends")
        ]  # fmt: skip
        values = WinchProblem.from_scene(
            problem.scene, problem.control, elements=2, step=step
        ).parameter_values()
        exact, ends = (linearisation(values, parameters) for linearisation in pair)
        np.testing.assert_allclose(ends.error, exact.error, atol=1e-12)
        gaps.append(np.linalg.norm(ends.jacobian - exact.jacobian) / np.linalg.norm(exact.jacobian))
    assert max(gaps) < 1e-5
    assert gaps[1] < gaps[0] / 2


def test_a_sweep_carried_onto_a_finer_control_is_that_controls_own_sweep(problem):
    """The stage Jacobians of one sweep, propagated through a finer control's map (the adaptive
    grid's candidates, ErrorLinearisation.carried), give that control's own Jacobian at the same
    profile to round-off; the coarse Jacobian is its restriction; after another sweep has written
    the shared arrays, nothing is carried."""
    from cable_ocp.control.adaptive_grid import on_nodes

    coarse_control, fine_control = HermiteIntervals(30.0, 3), HermiteIntervals(30.0, 6)
    coarse, fine = (_linearisation(problem, c) for c in (coarse_control, fine_control))
    values = problem.parameter_values()
    profile = 0.2 * np.random.default_rng(5).normal(size=coarse_control.size)
    swept = coarse(values, profile)
    carried = fine.carried(coarse, swept.jacobian)
    embedding = on_nodes(coarse_control, np.eye(coarse_control.size), fine_control.breakpoints)
    own = fine(values, embedding @ profile)
    scale = np.max(np.abs(own.jacobian))
    np.testing.assert_allclose(carried, own.jacobian, rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(carried @ embedding, swept.jacobian, rtol=0, atol=1e-12 * scale)
    assert fine.carried(coarse, swept.jacobian) is None  # the fine sweep wrote the arrays since
    assert fine.carried(coarse, swept.jacobian.copy()) is None  # not the sweep's own Jacobian


def test_a_converged_solve_keeps_the_qp_step_it_ended_on(problem):
    """GaussNewton.final_step is the QP step a fresh call takes at the solve's end, bit for bit,
    and only there: not for another point, nor for another bias."""
    from dataclasses import replace

    solver = _solver(problem)
    values = problem.parameter_values()
    outcome = solver.solve(values, np.zeros(problem.control.size))
    assert outcome.success, outcome.status
    kept = solver.final_step(values, outcome.parameters)
    bounds = problem.bounds
    linearised = solver.linearised_at(values, outcome.parameters)
    fresh, _, _ = solver.step(linearised, outcome.parameters, bounds.lower, bounds.upper, {})
    np.testing.assert_array_equal(kept, fresh)
    assert solver.final_step(values, outcome.parameters + 1e-9) is None
    shifted = replace(values, bias=values.bias + 1e-3)
    assert solver.final_step(shifted, outcome.parameters) is None


def test_candidates_between_the_default_nodes_are_all_that_a_carried_sweep_propagates(problem):
    """The adaptive grid's candidates' Jacobian from the default grid's sweep, propagated only
    through the candidates between the default nodes (the rest from J_default = J_finer E),
    is the Jacobian propagated through all of them, to round-off."""
    from cable_ocp.control.adaptive_grid import _carried
    from cable_ocp.control.gauss_newton import GaussNewton, GaussNewtonSettings

    coarse = problem.with_control(HermiteIntervals(30.0, 3))
    fine = problem.with_control(HermiteIntervals(30.0, 6))
    default, finer = (GaussNewton(p, GaussNewtonSettings()) for p in (coarse, fine))
    values = coarse.parameter_values()
    profile = 0.2 * np.random.default_rng(7).normal(size=coarse.control.size)
    jacobian = default.linearisation(values, profile).jacobian
    whole = finer.linearisation.carried(default.linearisation, jacobian)
    halved = _carried(default, finer, jacobian)
    scale = np.max(np.abs(whole))
    np.testing.assert_allclose(halved, whole, rtol=0, atol=1e-12 * scale)
