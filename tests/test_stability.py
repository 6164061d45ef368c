"""The stability study: step bisection, Baumgarte drift, the singular-state message, the report."""

from __future__ import annotations

import numpy as np
import pytest

from cable_ocp.drive.drive import Drive
from cable_ocp.model.cable import CableModel
from cable_ocp.scene.schema import load_scene
from cable_ocp.simulation.integrate import SimulationError
from cable_ocp.simulation.run import simulate
from cable_ocp.simulation.statics import equilibrium
from cable_ocp.studies.stability import (
    DriftSizes,
    StepSearch,
    baumgarte_drift,
    largest_stable_step,
    pushed_scene,
    rk4_growth,
    run_length,
    run_stability,
    singular_states,
)

# Small searches: short runs, a coarse bracket (ratio 1.5).
QUICK = StepSearch(duration=2.0, min_steps=50, resolution=1.5)
TORSION_QUICK = StepSearch(duration=0.5, min_steps=50, resolution=1.5, linearised_samples=2)


@pytest.fixture(scope="module")
def end_force(models_dir):
    return load_scene(models_dir / "end_force.toml")


def pushed_run(scene, elements: int, step: float, duration: float, min_steps: int, tolerance):
    """An independent run of the pushed scene at ``step`` (raises SimulationError if unstable)."""
    local = pushed_scene(scene, elements, False).updated(
        {
            "numerics.step": step,
            "numerics.duration": run_length(step, duration, min_steps),
            "numerics.constraint_tolerance": tolerance,
        }
    )
    model = CableModel.from_scene(local)
    return simulate(
        local, model=model, initial_state=equilibrium(model, Drive.from_scene(local)).state
    )


def test_rk4_growth_on_the_imaginary_axis():
    """RK4's stability region meets the imaginary axis at |z| = 2 sqrt(2)."""
    assert rk4_growth(np.array([2j * np.sqrt(2)]))[0] == pytest.approx(1.0, abs=1e-12)
    assert rk4_growth(np.array([2.7j]))[0] < 1 < rk4_growth(np.array([2.9j]))[0]
    assert rk4_growth(np.array([-2.78]))[0] < 1 < rk4_growth(np.array([-2.8]))[0]


def test_bisection_brackets_the_limit(end_force):
    """n = 5 without torsion: a fresh run at the found step completes, one at twice it fails."""
    result = largest_stable_step(end_force, 5, False, search=QUICK)
    assert result.step < result.unstable_step <= 1.5 * result.step
    assert result.failure
    tolerance = StepSearch().tolerance  # largest_stable_step's default bond tolerance
    run = pushed_run(end_force, 5, result.step, 2.0, 50, tolerance)
    assert run.time[-1] == pytest.approx(result.duration)
    with pytest.raises(SimulationError):
        pushed_run(end_force, 5, 2 * result.step, 2.0, 50, tolerance)
    # Stable here also means accurate to a small fraction of the end's motion.
    assert result.quarter_step_difference < 0.1 * result.end_excursion


def test_limit_falls_with_elements(end_force, validation):
    """With torsion h_max falls about as 1/n: n = 15 is at least 2x below n = 5.

    The linearised limit agrees with the bisection to within the bracket's ratio and a margin.
    """
    coarse = largest_stable_step(end_force, 5, True, search=TORSION_QUICK)
    fine = largest_stable_step(end_force, 15, True, first_step=coarse.step, search=TORSION_QUICK)
    agreement = [result.step / result.linearised_step for result in (coarse, fine)]
    validation("largest stable RK4 step with torsion, end_force, n = 5 and 15",
               "second formulation", "linearised limit (eigenvalues of the FD Jacobian)",
               "bisected h_max at n = 5, 15 (ratio); bisected / linearised at n = 5, 15",
               f"{coarse.step:.3g} s, {fine.step:.3g} s ({coarse.step / fine.step:.1f}x); "
               f"{agreement[0]:.2f}, {agreement[1]:.2f}", "ratio > 2; 0.5 .. 2")  # fmt: skip
    assert fine.step < coarse.step / 2
    for result in (coarse, fine):
        assert "twist" in result.failure
        assert 0.5 < result.step / result.linearised_step < 2


def test_no_stabilisation_drifts_more(end_force, validation):
    """Sharp push, n = 5, h = 0.1 s: without Baumgarte the bonds drift over 10x further."""
    sizes = DriftSizes(elements=5, step=0.1, reference_step=0.01, duration=10)
    drift = baumgarte_drift(end_force, ((0.0, 0.0), (1.0, 1.0)), sizes)
    none, default = drift.runs
    assert not none.failure and not default.failure
    validation("Baumgarte stabilisation, sharp push, n = 5, h = 0.1 s, 10 s", "conservation",
               "the bonds Phi = 0", "max |Phi| without / with the default gains (1, 1)",
               f"{none.residual.max():.1e} / {default.residual.max():.1e} m",
               "none > 10x default")  # fmt: skip
    assert none.residual.max() > 10 * default.residual.max()
    # Without stabilisation the residual only grows: it ends at its largest.
    assert none.residual[-1] == pytest.approx(none.residual.max(), rel=0.05)
    assert default.residual[-1] < 0.1 * default.residual.max()


def test_singular_state_message(models_dir):
    cases = singular_states(load_scene(models_dir / "hanging.toml"))
    assert len(cases) == 2
    for case in cases:
        assert case.rejected
        assert "along the y axis" in case.message and "singular" in case.message
        assert "Rotate the scene" in case.message


def test_quick_study_writes_its_folder(models_dir, tmp_path):
    out = tmp_path / "stability"
    study = run_stability(out, models_dir, quick=True)
    assert sorted(p.name for p in out.iterdir()) == [
        ".cable_ocp-results",
        "baumgarte_drift.png",
        "knots.png",
        "stability.md",
        "stable_step.png",
    ]
    text = (out / "stability.md").read_text()
    assert "Largest stable RK4 step" in text and "Euler-angle singularity" in text
    # Capped at 2 iterations / 10 evaluations: recorded as not converged, never as a success.
    assert not any(r.result.success for r in study.knots.runs)
    assert "Maximum" in text


def test_a_knot_run_is_named_by_its_solver_and_searched_when_it_does_not_shoot():
    from types import SimpleNamespace

    from cable_ocp.studies.stability.knots import KnotRun

    def run(solver, corrected, history):
        return KnotRun(7, corrected, SimpleNamespace(solver=solver, history=history))

    corrected = run("gauss-newton", True, [0.3, 0.2])
    search = run("nelder-mead", False, [0.5, 0.2, 0.2, 0.1])
    assert corrected.method == "gauss-newton + correction" and not corrected.searched
    assert search.method == "nelder-mead" and search.searched
    assert search.evaluations_to_within(1.0) == 2  # within 0.2 m of its last 0.1 m
    assert not run("nelder-mead", False, []).searched


@pytest.mark.parametrize("resolution", [1.0, 0.5, float("nan")])
def test_a_step_search_that_cannot_end_is_refused_naming_its_field(resolution):
    with pytest.raises(ValueError, match=r"StepSearch\.resolution = .*must be > 1"):
        StepSearch(resolution=resolution)
