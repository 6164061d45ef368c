"""Studies (cable_ocp.studies.convergence): step halving of the locked winch on paper_flat."""

from __future__ import annotations

from cable_ocp.scene.schema import load_scene
from cable_ocp.studies import convergence as studies


def test_locked_winch_step_halving_on_paper_flat(models_dir, validation):
    flat_scene = load_scene(models_dir / "paper_flat.toml")
    assert flat_scene.model.elements == 15 and flat_scene.numerics.step == 0.05
    result = studies.step_halving(flat_scene)
    validation("paper_flat, locked winch, n = 15, h = 0.05 s, 210 s", "converged reference",
               "the same run at h / 2", "max |r_E(h) - r_E(h/2)|; rise of the end",
               f"{result.max_difference:.1e} m; {result.rise:.3f} m",
               "< 0.01 m; 6.5 .. 7.5 m (CONVENTIONS.md §6: about 7 m)")  # fmt: skip
    # h = 0.05 s against 0.025 s over 210 s: tolerance 1 cm.
    assert result.max_difference < 0.01
    # CONVENTIONS.md §6: the end rises about 7 m with the winch locked; 6.5..7.5 m.
    assert 6.5 < result.rise < 7.5
    assert "h = 0.05 s" in result.table()
