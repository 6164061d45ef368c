"""Huge requests (issue 24, class 4): refused up front when they cannot fit, streamed when they can.

References: CasADi's own B-spline fit and FITPACK's interpolating spline (``RectBivariateSpline``,
``s = 0``: the same not-a-knot bicubic) for the grid; the run cut into one CasADi call for the
chunked integration (bitwise); the arrays that ``HermiteIntervals.basis`` allocates for the
optimiser's memory estimate. No test asserts a wall-clock time: sizes and counts only.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
import xarray as xr
from scipy.interpolate import RectBivariateSpline

from cable_ocp.drive.controls import HermiteIntervals
from cable_ocp.drive.drive import Drive
from cable_ocp.model.cable import CableModel
from cable_ocp.scene import bathymetry
from cable_ocp.scene.schema import MAX_CURRENT_ROWS, SceneError, SeabedGrid, load_scene
from cable_ocp.simulation import integrate as integration
from cable_ocp.simulation import run as running
from cable_ocp.simulation import seabed as seabeds
from cable_ocp.simulation.budget import (
    MODEL_BUILD,
    check_memory,
    check_simulation_memory,
    model_build,
    optimisation_memory,
    simulation_memory,
    state_size,
)
from cable_ocp.simulation.run import simulate
from cable_ocp.simulation.statics import equilibrium

GRID_TOLERANCE = 1e-9  # m: the fitted spline against CasADi's and FITPACK's


def _surface_file(path, nx, ny):
    """A rough seabed (ridges, waves, a slope) on an nx x ny grid, 2 m apart, as netCDF."""
    x, y = np.arange(nx) * 2.0 - 100.0, np.arange(ny) * 2.0 - 150.0
    X, Y = np.meshgrid(x, y, indexing="ij")
    z = -300.0 + 0.02 * X + 4.0 * np.sin(X / 17.0) * np.cos(Y / 23.0) + 0.5 * np.sin(X / 3.1)
    xr.Dataset({"elevation": (("x", "y"), z)}, coords={"x": x, "y": y}).to_netcdf(path)
    return bathymetry.read_grid(path)


def _points(grid, count=2000, seed=5):
    rng = np.random.default_rng(seed)
    x = np.concatenate([rng.uniform(grid.x[0], grid.x[-1], count), grid.x[[0, -1, 0, -1]]])
    y = np.concatenate([rng.uniform(grid.y[0], grid.y[-1], count), grid.y[[0, 0, -1, -1]]])
    return x, y


def test_a_600_by_400_grid_is_the_interpolating_bicubic_spline(tmp_path):
    """The fitted spline is FITPACK's interpolating spline (1e-9 m), and its data linear in size."""
    grid = _surface_file(tmp_path / "big.nc", 600, 400)
    x, y = _points(grid)
    surface = seabeds.grid_surface(grid)
    ours = np.asarray(surface(np.vstack([x, y]))).ravel()
    fitpack = RectBivariateSpline(grid.x, grid.y, grid.elevation, kx=3, ky=3, s=0)(x, y, grid=False)
    assert np.abs(ours - fitpack).max() < GRID_TOLERANCE
    # The Function holds the coefficients: one number a point (and the knots), 8 bytes each.
    small = seabeds.grid_surface(_surface_file(tmp_path / "small.nc", 300, 200))
    ratio = len(surface.serialize()) / len(small.serialize())
    assert 3.8 < ratio < 4.2  # four times the points


def test_a_grid_is_casadis_own_spline_in_value_slope_and_curvature(tmp_path):
    """On a 120 x 80 grid: CasADi's whole-grid fit (the old build) within 1e-9 m, SX derivatives."""
    grid = _surface_file(tmp_path / "g.nc", 120, 80)
    old = ca.interpolant("old", "bspline", [grid.x, grid.y], grid.elevation.ravel(order="F"))
    new = seabeds.grid_surface(grid)
    point = ca.SX.sym("p", 2)
    derivatives = []
    for function in (old, new):
        z = function(point)
        both = ca.Function("d", [point], [z, ca.gradient(z, point), ca.hessian(z, point)[0]])
        x, y = _points(grid, 300)
        values = both.map(x.size)(np.vstack([x, y]))
        derivatives.append([np.asarray(v) for v in values])
    for was, now in zip(*derivatives, strict=True):
        assert np.abs(was - now).max() < GRID_TOLERANCE * max(1.0, np.abs(was).max())


def test_a_large_grid_shows_its_build(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(seabeds, "LARGE_GRID_POINTS", 100)
    seabeds.grid_surface(_surface_file(tmp_path / "g.nc", 20, 10))
    assert "bathymetry: 100%" in capsys.readouterr().err


def test_a_grid_that_cannot_fit_is_refused_before_it_is_read(tmp_path, monkeypatch):
    """The declared size decides: 300 x 200 points at 200 B a point against 1 MB available."""
    path = tmp_path / "survey.nc"
    _surface_file(path, 300, 200)
    monkeypatch.setattr(bathymetry, "available_memory", lambda: 10**6)
    bathymetry._read_cached.cache_clear()
    with pytest.raises(SceneError) as info:
        SeabedGrid(file=str(path))
    text = str(info.value)
    assert text.startswith(f"seabed.grid.file: {path}: a grid of 300 x 200 points needs about ")
    assert "0.012 GB for its spline (200 bytes a point), more than the 0.001 GB" in text
    assert "\n" not in text


# ----------------------------------------------------------------------------------------------
# Current profiles: a stated limit on the rows, since every row adds to the model.


def test_a_2000_row_current_profile_is_refused_naming_the_field(models_dir):
    rows = [{"z": -0.15 * k, "u": 0.3 * np.exp(-0.001 * k)} for k in range(2000)]
    with pytest.raises(SceneError) as info:
        load_scene(models_dir / "survey.toml", {"environment.current_profile": rows})
    assert str(info.value).startswith(
        f"environment.current_profile: 2000 rows; at most {MAX_CURRENT_ROWS}: each row adds"
    )
    allowed = rows[:MAX_CURRENT_ROWS]
    scene = load_scene(models_dir / "survey.toml", {"environment.current_profile": allowed})
    assert len(scene.environment.current_profile) == MAX_CURRENT_ROWS


@pytest.mark.parametrize("key", ["environment.current", "environment.current_profile"])
def test_a_current_faster_than_any_at_sea_is_refused_with_the_reason(models_dir, key):
    value = [0.0, 20.0, 0.0] if key == "environment.current" else [{"z": 0.0, "v": 20.0}]
    with pytest.raises(SceneError, match=r"= 20\.0 is out of range: must be >= -10 and <= 10 "
                       r"\(m/s\): currents at sea stay under 10 m/s"):  # fmt: skip
        load_scene(models_dir / "paper_hill.toml", {key: value})


# ----------------------------------------------------------------------------------------------
# Runs: refused up front when the kept outputs cannot fit; streamed in bounded calls otherwise.


def test_a_run_whose_outputs_cannot_fit_is_refused_before_any_work(models_dir, monkeypatch):
    """5e7 steps of hanging (n = 10) keeping every state: about 0.14 TB; no model is built."""
    scene = load_scene(
        models_dir / "hanging.toml", {"numerics.duration": 500.0, "numerics.step": 1e-5}
    )
    monkeypatch.setattr(CableModel, "from_scene", pytest.fail)
    with pytest.raises(ValueError) as info:
        simulate(scene)
    text = str(info.value)
    assert text.startswith(
        "numerics.output_every = 1 (numerics.step = 1e-05 s, numerics.duration = 500.0 s): "
        "5e+07 RK4 steps keeping 5e+07 states need about "
    )
    assert "over the limit of" in text and "numerics.output_every = " in text
    assert "\n" not in text


def test_the_estimate_counts_every_kept_array(models_dir):
    scene = load_scene(models_dir / "hanging.toml", {"numerics.output_every": 10})
    estimate = simulation_memory(scene)
    n, kept = scene.model.elements, estimate.kept
    assert kept == round(scene.numerics.duration / scene.numerics.step) // 10 + 1
    per_state = state_size(scene) + 15 + 3 * (n + 2) + (n + 1) + 3
    assert estimate.total == 2 * 8 * kept * per_state
    check_memory(estimate, "numerics.step = 1 s", "remedy", available=2 * estimate.total)
    with pytest.raises(ValueError, match=r"^numerics\.step = 1 s: .* over the limit .*; remedy$"):
        check_memory(estimate, "numerics.step = 1 s", "remedy", available=estimate.total)


def test_the_optimisers_estimate_covers_the_control_basis(models_dir):
    """HermiteIntervals.basis at the stage times of 600 steps: its arrays are in the estimate."""
    scene = load_scene(models_dir / "small_tow.toml")
    control = HermiteIntervals(scene.numerics.duration, 12)
    steps = 600
    step = scene.numerics.duration / steps
    times = np.repeat(np.arange(steps) * step, 3) + np.tile([0.0, step / 2, step], steps)
    # The three arrays (views of one), and the winch map stacked from them.
    allocated = 2 * sum(array.nbytes for array in control.basis(times))
    estimate = optimisation_memory(scene, step, parameters=control.size)
    assert dict(estimate.parts)["control basis"] >= allocated
    # --step 1e-5 on small_tow: the estimate (several GB) is refused on a small machine.
    huge = optimisation_memory(scene, 1e-5, elements=3, parameters=control.size)
    assert huge.total > 7e9
    with pytest.raises(ValueError, match=r"^optimizer\.step = 1e-05 s: 4e\+06 RK4 steps"):
        check_memory(huge, "optimizer.step = 1e-05 s", "a longer step", available=16 * 10**9)


@pytest.fixture(scope="module")
def small_hanging(models_dir):
    scene = load_scene(models_dir / "hanging.toml", {"model.elements": 5})
    model = CableModel.from_scene(scene)
    drive = Drive.from_scene(scene)
    return model, drive, equilibrium(model, drive).state


def _one_call(model, drive, x0, duration, step, output_every):
    """The run as one CasADi call (the integration before it was cut into calls)."""
    count = round(duration / step)
    times = np.arange(count) * step
    loops = integration.step_function(model, step).fold(output_every)
    loops = loops.mapaccum(count // output_every)
    inputs = drive.stage_inputs(times, step)
    return np.asarray(loops(x0, inputs)).T


@pytest.mark.parametrize("output_every", [1, 6, 7])
def test_a_run_cut_into_small_calls_has_the_numbers_of_one_call(
    small_hanging, monkeypatch, output_every
):
    """Calls of one unit (a clock that says every call took 100 s), folds of 4 steps or less."""
    model, drive, x0 = small_hanging
    x0 = x0 + 1e-3 * np.sin(np.arange(x0.size))  # moving
    expected = _one_call(model, drive, x0, 8.4, 0.01, output_every)
    monkeypatch.setattr(integration, "MAX_FOLD", 4)
    clock = iter(range(0, 10**9, 100))
    monkeypatch.setattr(integration.time, "perf_counter", lambda: float(next(clock)))
    sizes = []
    function = integration._segment_function

    def recording(model, step, compiled, inner, size):
        sizes.append((inner, size))
        return function(model, step, compiled, inner, size)

    monkeypatch.setattr(integration, "_segment_function", recording)
    run = integration.integrate(model, x0, drive, 8.4, 0.01, output_every, tolerance=1.0)
    np.testing.assert_array_equal(run.states[1:], expected)
    inner = {1: 1, 6: 3, 7: 1}[output_every]
    assert {call[0] for call in sizes} == {inner}
    assert sizes[0][1] == max(1, integration.PROBE_STEPS // inner)
    assert {size for _, size in sizes[1:]} == {1}  # each call "took" a second: one unit a call


def test_a_long_run_is_called_in_bounded_steps_and_checked_in_blocks(models_dir, monkeypatch):
    """40 000 steps keeping every 1000th: no array over the run's steps, calls of bounded size."""
    scene = load_scene(
        models_dir / "hanging.toml",
        {"model.elements": 5, "numerics.duration": 40.0, "numerics.step": 1e-3,
         "numerics.output_every": 1000},
    )  # fmt: skip
    largest = {"inputs": 0, "stage_inputs": 0}
    inputs, stage_inputs = Drive.inputs, Drive.stage_inputs

    def recorded_inputs(self, times, left=None):
        if left is None:  # not the stages of a call
            largest["inputs"] = max(largest["inputs"], np.size(times))
        return inputs(self, times, left)

    def recorded_stage_inputs(self, times, step):
        largest["stage_inputs"] = max(largest["stage_inputs"], np.size(times))
        return stage_inputs(self, times, step)

    monkeypatch.setattr(Drive, "inputs", recorded_inputs)
    monkeypatch.setattr(Drive, "stage_inputs", recorded_stage_inputs)
    trajectory = simulate(scene)
    assert trajectory.time.size == 41
    assert largest["inputs"] <= running.TIME_BLOCK < 40_000
    assert largest["stage_inputs"] <= integration.MAX_CALL_STEPS


def test_the_model_builds_estimate_passes_through_its_measurements():
    for compiled, points in MODEL_BUILD.items():
        for n, size, seconds in points:
            assert model_build(n, compiled) == pytest.approx((size, seconds), rel=1e-12)
        sizes = [model_build(n, compiled)[0] for n in (15, 100, 300, 1000)]
        assert sizes == sorted(sizes)
    # The symbolic statics of the interpreted model outgrow the compiled build.
    assert model_build(1000, False)[0] > 10 * model_build(1000, True)[0]


def test_a_scene_of_1000_elements_is_refused_before_its_model_is_built(models_dir, monkeypatch):
    """Issue 45 item 9 (a saved scene edited to n = 1000): refused up front, with the estimate
    and the largest n that fits; here on small_tow, interpreted, on a 16 GB machine, and
    compiled on a 1 GB one. Nothing is built (CableModel would fail the test)."""
    monkeypatch.setattr(CableModel, "from_scene", lambda *a, **k: pytest.fail("built"))
    scene = load_scene(models_dir / "small_tow.toml", {"model.elements": 1000})
    with pytest.raises(ValueError) as info:
        check_simulation_memory(scene, available=16 * 10**9, compiled=False)
    text = str(info.value)
    assert text.startswith("model.elements = 1000: building the interpreted model (its statics)")
    assert "over the limit of 12.8 GB (80% of the 16 GB available)" in text and "\n" not in text
    most = int(text.split("; model.elements = ")[1].split()[0])
    assert 300 < most < 1000 and text.endswith(
        "or fewer fits, or the compiled model (not --interpreted)"
    )
    fitting = load_scene(models_dir / "small_tow.toml", {"model.elements": most})
    check_simulation_memory(fitting, available=16 * 10**9, compiled=False)
    check_simulation_memory(scene, available=16 * 10**9, compiled=True)
    with pytest.raises(
        ValueError,
        match=r"^model\.elements = 1000: building the compiled model "
        r"\(its statics and C library\) needs about 1\.2\d GB and \d+ s",
    ):
        check_simulation_memory(scene, available=10**9, compiled=True)
