"""The settings objects: one check each, their agreement checked by the registry, and a result's
settings rebuilt from its file."""

from __future__ import annotations

import pytest

import cable_ocp as co
from cable_ocp.control.closed_loop.settings import MpcSettings
from cable_ocp.control.settings import OcpSettings
from cable_ocp.control.solvers import SOLVERS, ocp_settings, ocp_settings_from, solver_of
from cable_ocp.scene.bundled import scene_path


def test_the_registry_names_each_solver_with_its_settings_class():
    assert list(SOLVERS) == ["gauss-newton", "ipopt", "nelder-mead"]
    for name, entry in SOLVERS.items():
        assert entry.name == name and entry.settings().__class__ is entry.settings
        assert solver_of(None, entry.settings())[0] is entry  # the settings name their solver
    assert [n for n, e in SOLVERS.items() if e.closed_loop] == ["gauss-newton", "ipopt"]
    with pytest.raises(ValueError, match="solver = 'nelder-mead': must be one of 'gauss-newton'"):
        solver_of("nelder-mead", None, closed_loop=True)
    with pytest.raises(ValueError, match="dict is no solver's settings"):
        solver_of(None, {})


def test_a_flat_table_goes_to_the_objects_that_declare_its_fields():
    settings = ocp_settings_from({"solver": "ipopt", "elements": 4, "intervals": 8,
                                  "shooting": "multiple", "hessian": "limited-memory"})  # fmt: skip
    assert isinstance(settings, OcpSettings) and settings.solver == "ipopt"
    assert (settings.model.elements, settings.grid.intervals) == (4, 8)
    assert settings.transcription.shooting == "multiple"
    with pytest.raises(ValueError, match="hessian: unknown setting for solver 'gauss-newton'"):
        ocp_settings_from({"hessian": "exact"})
    with pytest.raises(ValueError, match="an OcpSettings holds the solver"):
        ocp_settings("ipopt", settings)


# IPOPT's closed loop takes 15 s of the default run's 8-10 min: the same record, slow.
@pytest.mark.parametrize("solver", ["gauss-newton", pytest.param("ipopt", marks=pytest.mark.slow)])
def test_an_mpc_result_keeps_its_settings_and_runs_again_from_its_file(solver, tmp_path):
    """A heaving small_tow in a closed loop with settings of its own: the file's scene and
    settings run the same loop again (Omega to 1e-9 m)."""
    heave = {"top.heave.amplitude": 0.5, "top.heave.period": 8.0, "numerics.duration": 20.0}
    scene = co.load_scene(scene_path("small_tow"), heave)
    chosen = MpcSettings(horizon=12.0, sample=2.0, solver=solver, rate_weight=2e-4,
                         model=co.ModelSettings(elements=3))  # fmt: skip
    first = co.mpc(scene, chosen, quiet=True)
    first.save(tmp_path / "m")
    kept = co.load_result(tmp_path / "m")
    settings = MpcSettings.from_record(kept.settings)
    assert settings == chosen.resolved(scene)[0]
    again = co.mpc(kept.scene, settings, quiet=True)
    assert abs(again.omega - first.omega) < 1e-9
    with pytest.raises(ValueError, match="not a record of MpcSettings"):
        MpcSettings.from_record({"horizon_s": 10.0})


def test_a_derived_plan_interval_divides_the_horizon_the_user_fixed():
    """Horizon 10 s at a 2 s sample: intervals of 5 s would not divide it, so the derived
    interval is the multiple of the sample nearest 5 s that does (2 s; 10 s is farther)."""
    scene = co.load_scene(scene_path("small_tow"), {"numerics.duration": 20.0})
    settings, derived = MpcSettings(horizon=10.0, sample=2.0).resolved(scene)
    assert (settings.horizon, settings.interval) == (10.0, 2.0)
    assert "plan intervals of 2 s" in derived
    assert MpcSettings(horizon=12.0, sample=2.0).resolved(scene)[0].interval == 4.0
