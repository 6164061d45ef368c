"""The compiled step-end tangent against the numpy propagation; its fallback without a compiler."""

from __future__ import annotations

import numpy as np
import pytest

from cable_ocp.control import step_end_tangent
from cable_ocp.control.linearisation import propagate_sensitivities, winch_map
from cable_ocp.drive.controls import HermiteIntervals
from cable_ocp.drive.drive import stage_times
from cable_ocp.model import compile as compile_module


def step_end_case(seed: int, nx: int, steps: int, intervals: int, h: float = 0.05):
    """Random Jacobians at the RK4 points and a free-start Hermite winch map over the steps."""
    rng = np.random.default_rng(seed)
    control = HermiteIntervals(steps * h, intervals, free_start=True)
    times, left = stage_times(np.arange(steps) * h, h)
    winch = winch_map(control, times, left, 0.9)
    # The right-hand side's structure: coordinates' rates are the velocities, the rest dense.
    half = nx // 2
    pattern = np.zeros((nx, nx + 3), bool)
    pattern[:half, half:nx] = np.eye(half, dtype=bool)
    pattern[half:] = rng.random((nx - half, nx + 3)) < 0.8
    points = rng.normal(size=(steps + 1, nx + 3, nx)) / np.sqrt(nx) * pattern.T
    return points, winch, h


@pytest.mark.parametrize(
    ("seed", "nx", "steps", "intervals"), [(0, 30, 400, 4), (1, 8, 37, 3), (2, 10, 50, 2)]
)
def test_the_compiled_tangent_equals_the_numpy_propagation(seed, nx, steps, intervals):
    """Same arithmetic in another order: equal to 1e-13 of the sensitivities' size (measured
    2e-15), zero at the start, and the kept components only."""
    points, winch, h = step_end_case(seed, nx, steps, intervals)
    kernel = step_end_tangent.step_end_kernel(nx)
    assert kernel is not None  # the test machine has a compiler
    tangent = step_end_tangent.StepEndTangent(kernel, steps, nx, winch.shape[2], 3, h)
    compiled = tangent(points, winch)
    mean = 0.5 * (points[:-1] + points[1:])
    expected = propagate_sensitivities((points[:-1], mean, mean, points[1:]), winch, h, kept=3)
    assert compiled.shape == expected.shape == (steps + 1, winch.shape[2], 3)
    assert np.all(compiled[0] == 0.0)
    scale = np.max(np.abs(expected))
    assert scale > 1e-3
    assert np.max(np.abs(compiled - expected)) <= 1e-13 * scale
    # A second call reuses the scratch and gives the same numbers.
    assert np.array_equal(tangent(points, winch), compiled)


def test_without_a_compiler_the_kernel_is_none_with_a_warning(tmp_path, monkeypatch):
    monkeypatch.setenv("CABLE_OCP_CACHE", str(tmp_path))
    monkeypatch.setenv("CC", "/bin/false")
    with pytest.warns(RuntimeWarning, match=r"(?s)compiling step_end_tangent.c .* runs in numpy"):
        assert compile_module.compiled_source(step_end_tangent.SOURCE, {"NX": 30}) is None
    assert list(tmp_path.glob("*.so*")) == []  # nothing half-built is left behind


def test_the_kernel_is_compiled_once_then_loaded_from_the_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("CABLE_OCP_CACHE", str(tmp_path))
    library = compile_module.compiled_source(step_end_tangent.SOURCE, {"NX": 30})
    assert library is not None and library.parent == tmp_path
    assert compile_module.damage(library) is None
    stamp = library.stat().st_mtime_ns
    assert compile_module.compiled_source(step_end_tangent.SOURCE, {"NX": 30}) == library
    assert library.stat().st_mtime_ns == stamp
