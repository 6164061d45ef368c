"""The solver registry: each solver's capabilities asked of its entry, never its name compared;
the API's keywords checked where they enter."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

import cable_ocp as co
from cable_ocp.control.closed_loop.settings import CLOSED_LOOP_SOLVERS, MpcSettings
from cable_ocp.control.gauss_newton import DAQP_INFEASIBLE, GaussNewtonSettings
from cable_ocp.control.ipopt import IpoptSettings
from cable_ocp.control.solvers import (
    KNOTS,
    SHOOTING,
    SOLVERS,
    ocp_settings,
    ocp_settings_from_record,
    solver_for,
    transcription_named,
)

PACKAGE = Path(co.__file__).parent
# A solver's name compared as a string (issue 41's grep).
NAME_COMPARISON = re.compile(
    r'(==|!=|in \()\s*[\(\[]?"(ipopt|gauss-newton|nelder-mead|sqp|daqp|osqp|qrqp)'
)


def test_no_solver_name_is_compared_outside_the_registry():
    found = [
        f"{path.relative_to(PACKAGE)}:{number}: {line.strip()}"
        for path in sorted(PACKAGE.rglob("*.py"))
        if path != PACKAGE / "control" / "solvers.py"
        for number, line in enumerate(path.read_text().splitlines(), 1)
        if NAME_COMPARISON.search(line)
    ]
    assert not found, "\n".join(found)


def test_each_entry_states_its_capabilities():
    gauss_newton, ipopt, nelder_mead = SOLVERS.values()
    assert [e.transcription for e in SOLVERS.values()] == [SHOOTING, SHOOTING, KNOTS]
    assert [e.default_control for e in SOLVERS.values()] == ["hermite", "hermite", "spline"]
    assert [e.needs_compiled for e in SOLVERS.values()] == [True, False, False]
    assert [e.closed_loop_shooting for e in SOLVERS.values()] == ["single", "multiple", None]
    # The closed loop's defaults, as they were before they moved into the registry.
    assert gauss_newton.closed_loop_settings == GaussNewtonSettings(
        max_iter=1, real_time=True, stage_jacobians="ends"
    )
    assert ipopt.closed_loop_settings == IpoptSettings(tolerance=1e-6)
    assert CLOSED_LOOP_SOLVERS == {
        "gauss-newton": gauss_newton.closed_loop_settings,
        "ipopt": ipopt.closed_loop_settings,
    }
    assert MpcSettings(solver="ipopt").solver == "ipopt"
    # IPOPT warm-starts in the closed loop (the user's options win); the others run as given.
    started = ipopt.warm_started(IpoptSettings(ipopt_options={"mu_init": 0.1}))
    assert started.ipopt_options == {"warm_start_init_point": "yes", "mu_init": 0.1}
    assert (
        gauss_newton.warm_started(gauss_newton.closed_loop_settings)
        == gauss_newton.closed_loop_settings
    )
    assert nelder_mead.warm_started(nelder_mead.settings()) == nelder_mead.settings()
    # Only the QP solver reports an infeasible QP, in its own words.
    assert [e.infeasible for e in SOLVERS.values()] == [DAQP_INFEASIBLE, None, None]


def test_the_settings_take_the_solvers_default_control():
    assert ocp_settings().control == "hermite"
    assert ocp_settings("nelder-mead").grid.control == "spline"
    # A record kept before the control was filled in (grid.control None) rebuilds the same.
    record = ocp_settings("nelder-mead").record()
    record["grid"]["control"] = None
    assert ocp_settings_from_record(record) == ocp_settings("nelder-mead")


def test_the_registry_checks_what_a_solver_needs():
    with pytest.raises(ValueError, match="compiled = False: Gauss-Newton works on the compiled"):
        ocp_settings(transcription=co.TranscriptionSettings(compiled=False))
    with pytest.raises(ValueError, match="solver='ipopt' takes 'multiple'"):
        ocp_settings(transcription=co.TranscriptionSettings(shooting="multiple"))
    with pytest.raises(ValueError, match="ipopt_options .*IPOPT refuses them"):
        ocp_settings("ipopt", IpoptSettings(ipopt_options={"no_such_option": 1}))


def test_transcriptions_by_name_old_names_too():
    assert transcription_named("shooting") is SHOOTING
    assert transcription_named("ipopt") is SHOOTING  # files of before the solvers were named
    assert transcription_named("nelder-mead") is KNOTS
    with pytest.raises(ValueError, match="method = 'simplex': must be one of 'shooting', 'nel"):
        transcription_named("simplex")


def test_a_named_transcription_picks_or_checks_its_solver():
    assert solver_for(None, None) is None
    assert solver_for(None, "nelder-mead") == "nelder-mead"
    assert solver_for("shooting", None) == "gauss-newton"
    assert solver_for("ipopt", "ipopt") == "ipopt"
    assert solver_for("nelder-mead", None) == "nelder-mead"
    with pytest.raises(ValueError, match="that method is run by 'nelder-mead'"):
        solver_for("nelder-mead", "ipopt")
    with pytest.raises(ValueError, match="'gauss-newton' or 'ipopt'"):
        solver_for("shooting", "nelder-mead")


@pytest.mark.parametrize("front", [co.optimize, co.mpc])
def test_the_keyword_of_the_previous_release_says_what_it_became(front):
    # Refused where it enters: the scene (a name that is no scene) is never looked at.
    with pytest.raises(TypeError, match=r"the keyword 'method' is now 'solver'.*solver='ipopt'"):
        front("no such scene", method="ipopt")


@pytest.mark.parametrize(
    ("front", "keyword", "allowed"),
    [(co.optimize, "max_iter", "refinements"), (co.mpc, "horizn", "horizon")],
)
def test_an_unknown_keyword_is_refused_naming_the_allowed_ones(front, keyword, allowed):
    with pytest.raises(TypeError, match=rf"unknown keyword '{keyword}'; allowed: .*{allowed}"):
        front("no such scene", **{keyword: 1})


def test_refinements_for_a_solver_without_model_correction_are_refused():
    with pytest.raises(ValueError, match="refinements = 2: Nelder-Mead refines by no model"):
        co.optimize("hanging", "nelder-mead", refinements=2, quiet=True)
