"""The speed-accuracy study (cable_ocp.studies.speed_accuracy): quick run and Pareto front."""

from __future__ import annotations

import math

import numpy as np
import pytest

from cable_ocp.studies.speed_accuracy import QUICK_PLAN, pareto_front, run_speed_accuracy

# DOP853 at rtol = atol = 1e-10 against RK4 at h = 1/64 s on the same model, over 10-20 s (m).
REFERENCE_AGREEMENT = 1e-6


@pytest.fixture(scope="module")
def quick(tmp_path_factory, models_dir):
    out = tmp_path_factory.mktemp("speed") / "speed_accuracy"
    return out, run_speed_accuracy(out, models_dir, quick=True)


def dominated(k: int, costs, errors) -> bool:
    """Whether another point is no worse in both and better in one."""
    return any(
        c <= costs[k] and e <= errors[k] and (c < costs[k] or e < errors[k])
        for c, e in zip(costs, errors, strict=True)
    )


def test_pareto_front_on_synthetic_points():
    costs = [1.0, 2.0, 3.0, 4.0, 5.0, 0.5]
    errors = [10.0, 5.0, 6.0, 1.0, 1.0, 20.0]
    assert pareto_front(costs, errors) == [5, 0, 1, 3]
    rng = np.random.default_rng(3)
    costs, errors = rng.lognormal(size=200), rng.lognormal(size=200)
    front = set(pareto_front(costs, errors))
    for k in range(200):
        assert (k in front) == (not dominated(k, costs, errors))


def test_reference_agrees_with_fine_rk4(quick, validation):
    _, result = quick
    for study in result.scenes:
        validation(f"speed-accuracy reference, {study.scene_name} (quick size)",
                   "converged reference", "RK4 at a fine step (independent integrator)",
                   "max end difference of the adaptive DOP853 reference",
                   f"{study.reference.check_difference:.1e} m",
                   f"< {REFERENCE_AGREEMENT:g} m")  # fmt: skip
        assert study.reference.check_difference < REFERENCE_AGREEMENT, study.scene_name


def test_error_falls_with_the_step_at_the_reference_n(quick):
    # At the reference's n only the time discretisation is left, so RK4's error must fall with h.
    _, result = quick
    for study in result.scenes:
        runs = [p for p in study.stable_points if p.elements == QUICK_PLAN.reference_elements]
        runs.sort(key=lambda p: p.step)
        assert len(runs) >= 2, study.scene_name
        errors = [p.error for p in runs]
        assert errors == sorted(errors), (study.scene_name, errors)
        assert errors[0] < errors[-1] / 4


def test_failed_runs_are_recorded_not_ranked(quick):
    _, result = quick
    for study in result.scenes:
        for p in study.points:
            assert p.stable == math.isfinite(p.error)
            if not p.stable:
                assert p.message
        ranked = study.pareto() + [study.cheapest(t) for t in (0.01, 0.1)]
        assert all(p is None or p.stable for p in ranked)
    assert result.ocp and not result.ocp[0].result.success  # one iteration cannot converge


def test_files_are_written(quick):
    out, result = quick
    names = {".cable_ocp-results", "speed_accuracy.md", "ocp_omega_vs_time.png"}
    names |= {f"speed_accuracy_{s.scene_name}.png" for s in result.scenes}
    assert {p.name for p in out.iterdir()} == names
    text = (out / "speed_accuracy.md").read_text()
    for study in result.scenes:
        assert f"## {study.scene_name}" in text
    assert result.ocp[0].result.status in text


def test_an_ocp_setting_takes_its_settings_and_options_from_the_registry():
    """A shooting solver is capped in iterations and refined; the knots' search in evaluations."""
    from cable_ocp.studies.speed_accuracy.plan import OcpSetting

    shooting = OcpSetting("gauss-newton", 4, 0.5, 7, refinements=2)
    settings = shooting.settings(10)
    assert settings.solver == "gauss-newton" and settings.solver_settings.max_iter == 7
    assert settings.grid.intervals == 10 and settings.model.elements == 4
    assert shooting.options == {"refinements": 2}
    assert shooting.label == "gauss-newton, n = 4, h = 0.5 s, <= 7 iterations, 2 refinements"

    search = OcpSetting("nelder-mead", 3, 0.5, 50, refinements=2, compiled=False)
    settings = search.settings(10)
    assert settings.solver_settings.max_evaluations == 50 and settings.grid.intervals is None
    assert not settings.transcription.compiled
    assert search.options == {}
    assert search.label == "nelder-mead, n = 3, h = 0.5 s, <= 50 evaluations"
