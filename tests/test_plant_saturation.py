"""The closed loop's plant carries a drum saturated at its limits (control/closed_loop/plant.py).

Across the kink of a saturated drum RK4 converges at first order only, so a sample in doubt is
run again with finer substeps (``plant.SUBSTEPS``) until its bonds hold.
"""

from __future__ import annotations

import pytest

from cable_ocp.control.closed_loop import mpc, plant
from cable_ocp.lowering.hold import hold_scene

# Deploy's hold in a steep sea: the heave feedback drives the drum into its 2 rad/s and
# 1.5 rad/s^2 limits within seconds.
STEEP_SEA = {
    "top.heave.sea_state.significant_height": 2.5,
    "top.heave.sea_state.peak_period": 7.0,
    "top.heave.sea_state.seed": 3,
}


@pytest.fixture(scope="module")
def steep_hold():
    return hold_scene("deploy", duration=60.0).updated(STEEP_SEA)


def test_a_saturated_drum_runs_to_the_end_on_finer_substeps(steep_hold):
    """At h / 16 the bonds opened beyond numerics.constraint_tolerance (1e-4 m) at t = 4-5 s;
    at h / 64 the loop runs its 60 s, the drum saturated for seconds and said so."""
    assert plant.SUBSTEPS[-1] == 64
    result = mpc(steep_hold, quiet=True)
    assert result.success, result.status
    assert result.time[-1] == pytest.approx(60.0)
    assert "the drum saturated at its rate or acceleration limit for" in result.status
    assert 0.05 < result.omega < 0.5  # m: a winch that cannot follow this sea holds it coarsely


def test_without_the_finest_substeps_the_same_hold_fails_naming_them(steep_hold, monkeypatch):
    """The case is one the finest substep is needed for: without it the plant stops, its error
    listing the bond residual at each step it tried."""
    monkeypatch.setattr(plant, "SUBSTEPS", plant.SUBSTEPS[:-1])
    result = mpc(steep_hold, quiet=True)
    assert not result.success
    assert "with step h = 0.003125 s" in result.status and "Remedy" in result.status
