"""MoorDyn as a peer code: the input file, a short tow against cable_ocp, and no moordyn at all."""

import sys
from pathlib import Path

import numpy as np
import pytest

import cable_ocp as co
from cable_ocp.studies import moordyn_compare as mc

MODELS = Path(__file__).resolve().parents[1] / "models"


@pytest.fixture(scope="module")
def scene():
    return co.load_scene(MODELS / "paper_flat.toml")


def elastic_stretch(scene) -> float:
    """Stretch of a line hanging under its submerged weight, w L^2 / (2 EA), m."""
    cable, water = scene.cable, scene.environment
    area = cable.cross_section_area
    weight = (cable.mass_per_length - water.water_density * area) * water.gravity
    return weight * cable.length**2 / (2 * cable.youngs_modulus * area)


def test_input_file_describes_the_scene_cable(scene):
    text = mc.moordyn_input(scene, 15, 5e-4, shift=1.0)
    cable_line = next(line for line in text.splitlines() if line.startswith("cable "))
    values = [float(v) for v in cable_line.split()[1:]]
    area, inertia = np.pi * 0.07**2 / 4, np.pi * 0.07**4 / 64
    # Diam, Mass/m, EA, BA, EI, Cd, Ca, CdAx, CaAx (CONVENTIONS.md §6)
    expected = [0.07, 6500 * area, 1e11 * area, 0.0, 1e11 * inertia, 1.0, 1.0, 0.1, 0.0]
    assert values == pytest.approx(expected)
    assert "1 cable 1 2 300.0 15 -" in text
    assert "2 Coupled 0.0 0.0 -1.0 0 0 0 0" in text
    assert "1 Free 0.0 0.0 -301.0 0 0 0 0" in text


def test_moordyn_tow_agrees_with_cable_ocp(scene, validation):
    pytest.importorskip("moordyn")
    duration = 40.0
    theirs = mc.run_moordyn(scene, 15, 5e-4, duration)
    ours = co.simulate(scene.updated({"numerics.duration": duration}))
    every = round(mc.SAMPLE_STEP / scene.numerics.step)
    ours_end = ours.end[::every]
    assert theirs.finite and ours_end.shape == theirs.end.shape
    difference = np.linalg.norm(theirs.end - ours_end, axis=1)
    stretch = elastic_stretch(scene)  # 2.4 cm: MoorDyn's line is extensible, ours is not
    # At rest the only difference is MoorDyn's elastic stretch.
    assert difference[0] == pytest.approx(stretch, abs=1e-3)
    # Under way the two discretisations at N = 15 place drag and mass differently (lumped at
    # nodes vs Gauss points on rigid elements) and MoorDyn's tension travels at the axial wave
    # speed: allow on top the accuracy asked of any run (1 cm) and 1 % of the end's displacement.
    displacement = np.linalg.norm(ours_end - ours_end[0], axis=1)
    assert displacement[-1] > 5.0  # the end really moved
    excess = difference - stretch - 0.01 * displacement
    validation("paper_flat tow, locked winch, N = n = 15, 40 s", "peer code",
               "MoorDyn 2 (lumped mass, extensible), RK4 at 5e-4 s",
               "end difference at rest; max under way beyond stretch + 1 % of displacement",
               f"{difference[0]:.4f} m (stretch {stretch:.4f} m); {excess.max():.4f} m",
               f"stretch +- 1 mm; <= {mc.STEP_TOLERANCE} m")  # fmt: skip
    assert np.all(excess <= mc.STEP_TOLERANCE)


def test_report_without_moordyn_says_how_to_install(monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "moordyn", None)  # makes `import moordyn` raise ImportError
    assert mc.moordyn_report(MODELS) == []
    out = capsys.readouterr().out
    assert out.count("\n") == 1
    assert 'python -m pip install -e ".[bench]"' in out
