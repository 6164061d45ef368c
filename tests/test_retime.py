"""An optimum replayed on a scene of another duration: refused, or retimed by choice (issue 45, 3).

Cases of our own: a 12 s optimum of four spline knots on the hanging scene, replayed over 30 s
and 6 s (the issue's were 60 s over 210 s and 420 s).
"""

import numpy as np
import pytest

import cable_ocp as co
from cable_ocp.control.optimization import OcpResult

KNOTS = np.array([0.4, -0.3, 0.5, 0.2])  # rad


@pytest.fixture(scope="module")
def scenes(models_dir):
    base = co.load_scene(models_dir / "hanging.toml", {"winch.knots": 4})
    return {T: base.updated({"numerics.duration": T}) for T in (6.0, 12.0, 30.0)}


@pytest.fixture(scope="module")
def optimum(scenes):
    nan = float("nan")
    return OcpResult(
        method="nelder-mead", parameters=KNOTS, control="spline(4)", trajectory=None, omega=nan,
        omega_model=nan, success=True, status="made here", iterations=0, evaluations=0,
        wall_time=0.0, build_time=0.0, solve_time=0.0, function_time=0.0,
        scene_record=scenes[12.0].to_dict(),
    )  # fmt: skip


def test_another_duration_is_refused_naming_both_and_the_choices(scenes, optimum):
    for T in (30.0, 6.0):
        with pytest.raises(ValueError) as caught:
            co.simulate(scenes[T], winch=optimum)
        message = str(caught.value)
        assert f"numerics.duration = {T:g} s, but the winch profile was made for 12 s" in message
        assert "result.retimed('hold')" in message and "result.retimed('stretch')" in message
    with pytest.raises(ValueError, match=r"retime = 'loop': must be one of 'hold', 'stretch'"):
        optimum.retimed("loop")


def test_hold_plays_the_profile_in_its_own_time_then_brings_the_winch_to_rest(scenes, optimum):
    own = optimum.winch_profile(scenes[12.0])
    held = optimum.retimed("hold").winch_profile(scenes[30.0])
    t = np.linspace(0.0, 12.0, 241)
    for mine, theirs in zip(held(t), own(t), strict=True):
        np.testing.assert_allclose(mine, theirs, atol=1e-12)
    phi, rate, acceleration = held(np.array([12.0, 12.0 + 1e-6, 30.0]))
    assert phi[1] == pytest.approx(phi[0], abs=1e-5)  # continuous at the end
    assert abs(rate[2]) < 1e-3 * max(abs(rate[0]), 1e-3) and abs(acceleration[2]) < 1e-3
    shorter = optimum.retimed("hold").winch_profile(scenes[6.0])(np.array([6.0]))[0]
    assert shorter[0] == pytest.approx(own(np.array([6.0]))[0][0])  # cut, not squeezed
    assert "the 12 s optimum played in its own time" in optimum.retimed("hold").note(scenes[30.0])
    assert optimum.retimed("hold").note(scenes[12.0]) == ""


def test_stretch_lays_the_knots_over_the_scene_and_the_same_duration_is_unchanged(scenes, optimum):
    stretched = optimum.retimed("stretch").winch_profile(scenes[30.0])
    assert stretched(np.array([30.0]))[0][0] == pytest.approx(KNOTS[-1])
    assert stretched(np.array([7.5]))[0][0] == pytest.approx(KNOTS[0])  # knot 1 at T/4
    own = optimum.winch_profile(scenes[12.0])
    assert own(np.array([3.0]))[0][0] == pytest.approx(KNOTS[0])


def test_a_held_replay_runs_and_keeps_its_bonds(scenes, optimum):
    run = co.simulate(scenes[30.0], winch=optimum.retimed("hold"))
    assert run.time[-1] == pytest.approx(30.0)
    played = optimum.winch_profile(scenes[12.0])(run.time[run.time <= 12.0])[0]
    np.testing.assert_allclose(run.winch_angle[run.time <= 12.0], played, atol=1e-12)
    late = run.time >= 25.0
    assert np.ptp(run.winch_angle[late]) < 1e-3  # at rest, held
