"""MoorDyn's deep-lowering reference (issue 44): the analytic figures and a free decay."""

import math

import numpy as np
import pytest

from cable_ocp.drive.drive import Drive
from cable_ocp.studies import moordyn_deep as md


@pytest.fixture(scope="module")
def deploy_line():
    """Deploy's 5 t frame on 1000 m of 40 mm steel wire, the vessel heaving."""
    return next(case for case in md.CASES if case.name == "steel_1000m_5t").scene()


def test_axial_period_and_statics_by_hand(deploy_line):
    # m = 7850 pi 0.02^2 = 9.8646 kg/m, EA = 1e11 pi 0.02^2 = 1.25664e8 N,
    # A33 = 1025 x 0.64 = 656 kg
    # T0 = 2 pi sqrt((5000 + 656 + 9.8646 x 1000 / 3) / (1.25664e8 / 1000)) = 2 pi x 0.26679
    assert md.axial_period(deploy_line) == pytest.approx(1.6763, abs=1e-4)
    # W_p = (5000 - 656) 9.81 = 42614.6 N, w' = (7850 - 1025) pi 0.02^2 9.81 = 84.136 N/m
    assert md.static_top_tension(deploy_line) == pytest.approx(42614.6 + 84136.0, abs=1.0)
    # (42614.6 x 1000 + 84.136 x 1000^2 / 2) / 1.25664e8
    assert md.static_stretch(deploy_line) == pytest.approx(0.67388, abs=1e-5)
    # The continuum's first root of x tan x = 9864.6 / 5656: x = 1.0349, T = 2 pi L / (x c)
    assert md.axial_period_exact(deploy_line) == pytest.approx(1.7006, abs=1e-3)


def test_axial_damping_maps_the_ratio_to_ba(deploy_line):
    period, stiffness = md.axial_period(deploy_line), 1e11 * math.pi * 0.02**2
    assert md.axial_damping(deploy_line, 0.02) == pytest.approx(0.02 * stiffness * period / math.pi)
    with pytest.raises(ValueError, match="ratio = 1.5 is out of range"):
        md.axial_damping(deploy_line, 1.5)


def test_input_file_carries_the_payload_and_the_damping(deploy_line):
    text = md.moordyn_input(deploy_line, 20, 1e-3, shift=1.0, ratio=0.02)
    rows = text.splitlines()
    cable = next(row for row in rows if row.startswith("cable ")).split()
    assert float(cable[4]) == pytest.approx(md.axial_damping(deploy_line, 0.02))
    payload = [float(v) for v in next(row for row in rows if row.startswith("1 Free ")).split()[2:]]
    # X Y Z (the stretched end), Mass Volume CdA (1.2 x 6.25) Ca
    assert payload == pytest.approx([0.0, 0.0, -1001.67388, 5000.0, 0.64, 7.5, 1.0], abs=1e-5)
    assert rows.index("1e-6 threshIC") < len(rows) - 1


def test_bad_run_settings_are_refused_by_name(deploy_line):
    top = Drive.from_scene(deploy_line).top
    with pytest.raises(ValueError, match="segments = 0 is out of range"):
        md.run_moordyn(deploy_line, top, 10.0, 0)
    with pytest.raises(ValueError, match="duration = 0.0 s is out of range"):
        md.run_moordyn(deploy_line, top, 0.0, 20)
    with pytest.raises(ValueError, match="step = 0.1 s is out of range"):
        md.run_moordyn(deploy_line, top, 10.0, 20, step=0.1)


def test_internal_step_shrinks_with_the_segments(deploy_line):
    coarse, fine = md.internal_step(deploy_line, 20), md.internal_step(deploy_line, 40)
    assert coarse in md.mc.MOORDYN_STEPS and fine < coarse


@pytest.fixture(scope="module")
def shortest():
    return min(md.CASES, key=lambda case: md.axial_period(case.scene()))


def test_free_decay_period_matches_the_analytic_one(shortest):
    pytest.importorskip("moordyn")
    scene = shortest.scene(heave=False)
    run = md.decay_run(scene, shortest.segments)
    assert run.stretch == pytest.approx(md.static_stretch(scene), rel=1e-4)  # started at rest
    period = md.decay_period(run.time, run.top, run.payload)
    assert period == pytest.approx(md.axial_period(scene), rel=0.03)
    assert period == pytest.approx(md.axial_period_exact(scene), rel=0.002)


def test_free_decay_damping_is_the_ratio_asked(shortest):
    """Without drag, the decay's damping ratio is the one BA was set for (2 % of T0's mode)."""
    pytest.importorskip("moordyn")
    scene = shortest.scene(heave=False)
    scene = scene.updated({"hydrodynamics.drag": False, "end.payload.drag_area": 0.0})
    run = md.decay_run(scene, shortest.segments)
    ratio = md.decay_damping_ratio(run.time, run.top, run.payload)
    # BA is set on the Rayleigh period; the exact mode is slower, so zeta is T0 / T_exact lower.
    expected = md.DAMPING_RATIO * md.axial_period(scene) / md.axial_period_exact(scene)
    assert ratio == pytest.approx(expected, rel=0.05)


def test_a_stiff_line_carries_the_heave_to_the_payload(shortest):
    """T0 1.1 s far below the sea's 9 s: the payload follows the top, the tension about static."""
    pytest.importorskip("moordyn")
    scene = shortest.scene()
    run = md.run_moordyn(scene, Drive.from_scene(scene).top, 40.0, shortest.segments)
    payload = run.payload - run.payload[0]
    assert np.corrcoef(payload, run.top)[0, 1] > 0.99
    assert np.std(payload) == pytest.approx(np.std(run.top), rel=0.1)
    assert np.mean(run.tension) == pytest.approx(md.static_top_tension(scene), rel=0.01)
