"""The package's layers (cable_ocp.studies.imports): no import points up, and the drawing."""

from __future__ import annotations

from cable_ocp.studies import imports


def test_every_module_is_in_a_layer_and_no_import_points_up():
    graph = imports.modules()
    assert {m.layer for m in graph} <= {layer for row in imports.LAYERS for layer in row}
    assert imports.violations() == []


def test_a_module_importing_from_above_is_reported(tmp_path):
    """A copy of the package with one upward import (model -> control) fails the check."""
    root = tmp_path / "cable_ocp"
    (root / "model").mkdir(parents=True)
    (root / "control").mkdir()
    for folder in (root, root / "model", root / "control"):
        (folder / "__init__.py").write_text('"""Package."""\n')
    (root / "control" / "shooting.py").write_text("from cable_ocp.model import cable\n")
    (root / "model" / "cable.py").write_text("from cable_ocp.control import shooting\n")
    assert imports.violations(root) == [
        "cable_ocp.model.cable (model) -> cable_ocp.control.shooting (control)"
    ]


def test_core_does_not_import_the_studies():
    below = {"scene", "model", "drive", "simulation", "control"}
    for module in imports.modules():
        if module.layer in below:
            assert not any(".studies" in name for name in module.imports), module.name


def test_drawing_is_written(tmp_path):
    path = imports.draw(tmp_path / "imports.png")
    assert path.stat().st_size > 10_000


def test_no_modules_import_each_other_round_a_loop():
    """No import cycle, counting imports inside functions too (issue 41)."""
    assert imports.cycles() == []


def test_a_cycle_through_a_local_import_is_reported(tmp_path):
    """A copy of the package where two modules import each other, one inside a function."""
    root = tmp_path / "cable_ocp"
    (root / "simulation").mkdir(parents=True)
    for folder in (root, root / "simulation"):
        (folder / "__init__.py").write_text('"""Package."""\n')
    (root / "simulation" / "run.py").write_text(
        "def simulate():\n    from cable_ocp.simulation.line_run import simulate_line\n"
    )
    (root / "simulation" / "line_run.py").write_text("from cable_ocp.simulation import run\n")
    (root / "simulation" / "outputs.py").write_text("from cable_ocp.simulation import run\n")
    assert imports.cycles(root) == [
        "cable_ocp.simulation.line_run -> cable_ocp.simulation.run -> cable_ocp.simulation.line_run"
    ]
