"""Model correction's full-model runs: their step, their accuracy, and their fallback."""

from __future__ import annotations

import numpy as np
import pytest

from cable_ocp.control import verification
from cable_ocp.control.verification import correction_step, fitted_step, verify_profile
from cable_ocp.drive.controls import HermiteIntervals
from cable_ocp.drive.drive import Drive
from cable_ocp.model.cable import CableModel
from cable_ocp.scene.schema import load_scene
from cable_ocp.simulation.run import simulate
from cable_ocp.simulation.seabed import rms_objective
from cable_ocp.simulation.stability import linearised_step
from cable_ocp.simulation.statics import starting_state


@pytest.fixture(scope="module")
def hill(models_dir):
    """paper_hill's first 40 s (n = 15, h = 0.05 s)."""
    return load_scene(models_dir / "paper_hill.toml", {"numerics.duration": 40.0})


def test_the_correction_step_is_a_power_of_two_well_inside_the_stability_limit(hill):
    """paper_hill's n = 15 model: the linearised RK4 limit at its start is 0.38 s (the stability
    study measured 0.38 s at n = 15 too), so 4 h = 0.2 s, at 0.53 of it."""
    model = CableModel.from_scene(hill)
    drive = Drive.from_scene(hill)
    start = starting_state(model, drive, compiled=True)
    limit = linearised_step(model, start, drive.inputs(np.zeros(1))[:, 0])
    assert limit == pytest.approx(0.378, abs=0.01)
    step = correction_step(hill, compiled=True)
    assert step == pytest.approx(4 * hill.numerics.step)
    assert step <= verification.CORRECTION_STABILITY_SHARE * limit


def test_a_correction_step_is_halved_until_the_nodes_fall_on_its_step_ends():
    """An adaptive grid's nodes kept (2.5 s apart here and there) take the correction step
    that fits them, never one below the scene's."""
    assert fitted_step(0.2, 0.05, [0.0, 5.0, 10.0]) == 0.2
    assert fitted_step(0.2, 0.05, [0.0, 2.5, 5.0]) == 0.1
    assert fitted_step(0.2, 0.05, [0.0, 2.55, 5.0]) == 0.05
    assert fitted_step(0.2, 0.05, [0.0, 2.525]) == 0.05  # off every step: the scene's


def test_a_correction_run_tracks_the_scenes_step(hill):
    """Under a brisk winch profile (the end moves by 0.76 m) the end's clearance error of the run
    at 4 h is within 1e-5 m of the run at the scene's step (measured 6.8e-6 m), and Omega on the
    same samples within 5e-6 m (measured 1.2e-6 m): the bias it gives the model correction is
    the scene's to well under paper_hill's optimum of 1.3e-4 m."""
    control = HermiteIntervals(hill.numerics.duration, 8)
    parameters = 0.5 * np.sin(np.arange(control.size))
    coarse = verify_profile(hill, control, parameters, compiled=True, step=0.2)
    fine = verify_profile(hill, control, parameters, compiled=True)
    assert coarse.step == pytest.approx(0.2) and fine.step == pytest.approx(0.05)
    assert coarse.trajectory is not None and fine.trajectory is not None
    times = coarse.trajectory.time
    error = np.interp(times, fine.trajectory.time, fine.trajectory.clearance_error)
    difference = np.max(np.abs(coarse.trajectory.clearance_error - error))
    print(f"largest e(t) difference, 4 h against h: {difference:.2e} m")
    assert difference < 1e-5
    # Omega on the same samples (the finer grid's trapezoid differs by 1e-5 m on a 0.45 m Omega).
    assert abs(coarse.trajectory.omega - rms_objective(times, error)) < 5e-6


def test_a_correction_run_that_blows_up_falls_back_to_the_scenes_step(hill):
    """A step far beyond the stability limit (1.6 s at n = 15) leaves the bonds; the run is then
    the scene's, and the note says which run failed."""
    control = HermiteIntervals(hill.numerics.duration, 8)
    parameters = np.zeros(control.size)
    checked = verify_profile(hill, control, parameters, compiled=True, step=1.6)
    assert checked.trajectory is not None, checked.reason
    assert checked.step == pytest.approx(hill.numerics.step)
    assert "h = 1.6 s failed" in checked.note


def test_the_runs_own_bond_check_is_the_residual_of_its_states(hill):
    """A run's bond_residual is the largest residual its integration checked: the same as
    evaluating the bond residuals of the returned states afresh (the states after the first)."""
    from cable_ocp.simulation.integrate import bond_residuals

    trajectory = simulate(hill, compiled=True)
    residual = trajectory.bond_residual
    model = CableModel.from_scene(hill)
    again = bond_residuals(model, trajectory.states, trajectory.inputs, compiled=True)
    assert residual == pytest.approx(float(again[1:].max()), rel=1e-12)
    assert 0 < residual < hill.numerics.constraint_tolerance


def test_a_profile_verified_again_at_the_same_step_gets_its_verdict_without_a_run(
    hill, monkeypatch
):
    """A model-correction solve that does not move the profile (6 of whole-space seed 0's first
    20 scenes) has it verified once: the same parameters at the same step (the scene's, however
    asked for) get the last verdict back; a profile one ulp away, or another step, is run."""
    from types import SimpleNamespace

    from cable_ocp.control import optimization

    runs = []

    def counted(scene, control, parameters, **options):
        runs.append(options.get("step"))
        return verify_profile(scene, control, parameters, **options)

    monkeypatch.setattr(optimization, "verify_profile", counted)
    control = HermiteIntervals(hill.numerics.duration, 8)
    problem = SimpleNamespace(scene=hill, control=control)
    verify, elapsed = optimization._timed_verify(problem, quiet=True, compiled=True)
    parameters = 0.5 * np.sin(np.arange(control.size))
    coarse = verify(parameters, 0.2)
    spent = elapsed()
    assert verify(parameters.copy(), 0.2) is coarse and len(runs) == 1 and elapsed() == spent
    fine = verify(parameters)
    assert fine is not coarse and fine.step == pytest.approx(hill.numerics.step)
    assert verify(parameters, hill.numerics.step) is fine and len(runs) == 2
    moved = parameters.copy()
    moved[3] = np.nextafter(moved[3], 1.0)
    assert verify(moved) is not fine and len(runs) == 3


def test_a_profile_under_which_the_rope_pushes_fails_with_the_remedy(models_dir):
    """The hanging rope with a 1 t load paid out 10 m in 3 s (tests/test_cli_physics.py): the
    verification fails, says where the rope pushed and what the winch's limits can change."""
    from cable_ocp.drive.controls import KnotSpline

    scene = load_scene(
        models_dir / "hanging.toml",
        {
            "numerics.duration": 6.0, "numerics.step": 0.01,
            "numerics.constraint_tolerance": 1e-4, "winch.top_length_max": 60.0,
            "winch.angle_max": 100.0,
            "end.payload": {"mass": 1000.0, "volume": 0.1, "drag_area": 1.0},
        },
    )  # fmt: skip
    tau = np.clip(np.arange(1, 15) * 6.0 / 14 / 3.0, 0.0, 1.0)
    knots = 10.0 / 0.5 * tau**3 * (10 - 15 * tau + 6 * tau**2)  # 10 m on the 0.5 m drum
    checked = verify_profile(scene, KnotSpline(6.0, 14), knots)
    assert checked.trajectory is None
    assert "the verified run is not physical: rope pushes" in checked.reason
    assert checked.reason.endswith(verification.PUSHING_REMEDY)
