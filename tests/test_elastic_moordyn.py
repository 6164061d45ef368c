"""The elastic rope against MoorDyn on deep lifts (issue 44, acceptance 1).

Four cases of :mod:`cable_ocp.studies.moordyn_deep` (steel and synthetic, T0 from 1.1 to 6.3 s):
a payload hanging from a vessel heaving in a JONSWAP sea (H_s 2 m, T_p 9 s), the winch locked,
2 % damping of the first axial mode; the same vessel motion and statistics window in both codes.
The project's default (``model.axial = "auto"``) must choose the elastic rope and match MoorDyn's
payload heave within 5 %, its top tension range within 10 %, and its free-decay period within 3 %.
"""

import pytest

from cable_ocp.scene.axial_choice import axial_choice
from cable_ocp.studies import elastic_deep as ed
from cable_ocp.studies import moordyn_deep as md

pytest.importorskip("moordyn")


@pytest.fixture(scope="module", params=md.CASES, ids=lambda case: case.name)
def compared(request):
    """``(case, the project's ElasticRun, MoorDyn's HeaveFigures, MoorDyn's decay period)``."""
    case = request.param
    scene = case.scene()
    moordyn_heave = md.heave_run(scene, case.segments)
    figures = md.heave_figures(
        moordyn_heave.time, moordyn_heave.top, moordyn_heave.payload, moordyn_heave.tension
    )
    decay = md.decay_run(case.scene(heave=False), case.segments)
    period = md.decay_period(decay.time, decay.top, decay.payload)
    return case, ed.elastic_run(case), figures, period


def test_auto_chooses_the_elastic_rope_on_every_deep_case():
    for case in md.CASES:
        assert axial_choice(ed.case_scene(case)).elastic, case.name


def test_heave_tension_and_period_match_moordyn(compared, validation):
    case, ours, theirs, their_period = compared
    heave = ours.figures.payload_heave_std / theirs.payload_heave_std - 1
    tension = ours.figures.tension_range / theirs.tension_range - 1
    period = ours.decay_period / their_period - 1
    validation(
        f"{case.name}: {case.length:.0f} m, EA {case.axial_stiffness / 1e6:.0f} MN, "
        f"{case.payload_mass / 1e3:.0f} t; Hs 2 m, Tp 9 s, winch locked, 600 s; "
        f"n = {ed.ELEMENTS}, h = {ed.STEP} s (model.axial = auto: elastic)",
        "peer code",
        f"MoorDyn 2, {case.segments} segments, BA for 2 % of the first axial mode",
        "payload heave std; top tension range; free-decay axial period",
        f"{ours.figures.payload_heave_std:.4f} / {theirs.payload_heave_std:.4f} m ({heave:+.1%}); "
        f"{ours.figures.tension_range / 1e3:.1f} / {theirs.tension_range / 1e3:.1f} kN "
        f"({tension:+.1%}); {ours.decay_period:.4f} / {their_period:.4f} s ({period:+.1%})",
        "within 5 %; 10 %; 3 %",
    )
    assert abs(heave) <= 0.05
    assert abs(tension) <= 0.10
    assert abs(period) <= 0.03
