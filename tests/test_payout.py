"""A line paid out and hauled in by elements (issue 26; CONVENTIONS.md §3, the line on the drum).

References independent of the code under test: the line out from the drum's angle
(``L_0 + r_D (phi - phi(0))``), the statics of a vertical rope (payload and line weights less
buoyancy), finite differences of the element axis, and the bonds evaluated by the model's own
outputs (a different path from the state maps).
"""

from __future__ import annotations

import numpy as np
import pytest
from conftest import MODELS, chained_state

import cable_ocp as co
from cable_ocp.model.cable import spec_from_scene
from cable_ocp.model.layout import INPUTS
from cable_ocp.model.line_models import LineModels
from cable_ocp.model.line_state import axis_rate, merge, momentum, split
from cable_ocp.simulation.line_trajectory import LineTrajectory
from cable_ocp.studies import payout_validation as pv

WATER, GRAVITY = 1025.0, 9.81
PAYLOAD = {"mass": 2000.0, "volume": 0.256, "drag_area": 1.0}  # 2 t of steel


def ramped_pay_out(speed: float, ramp: float, radius: float, reverse_at: float | None = None):
    """Drum angle paying out at ``speed`` (m/s) after a quintic ramp of ``ramp`` s.

    With ``reverse_at`` (s) the line comes back in at the same speed from then on (a C2 turn
    over ``ramp`` s).
    """

    def rate_shape(t):
        tau = np.clip(t / ramp, 0.0, 1.0)
        return 10 * tau**3 - 15 * tau**4 + 6 * tau**5

    def integral(t):
        tau = np.clip(t / ramp, 0.0, 1.0)
        return ramp * (2.5 * tau**4 - 3 * tau**5 + tau**6) + np.maximum(t - ramp, 0.0)

    def derivative(t):
        tau = np.clip(t / ramp, 0.0, 1.0)
        return (30 * tau**2 - 60 * tau**3 + 30 * tau**4) / ramp

    def angle(t, left=None):
        t = np.asarray(t, dtype=float)
        phi, rate, acc = integral(t), rate_shape(t), derivative(t)
        if reverse_at is not None:
            back = t - reverse_at
            phi = phi - 2 * np.where(back > 0, integral(back), 0.0)
            rate = rate - 2 * np.where(back > 0, rate_shape(back), 0.0)
            acc = acc - 2 * np.where(back > 0, derivative(back), 0.0)
        scale = speed / radius
        return scale * phi, scale * rate, scale * acc

    return angle


def line_scene(overrides: dict, **line) -> co.Scene:
    base = {
        "top.motion": "fixed",
        "numerics.constraint_tolerance": 1e-4,
        "winch.line": {"element_length": 10.0, **line},
        "end.payload": PAYLOAD,
    }
    return co.load_scene(MODELS / "paper_flat.toml", {**base, **overrides})


def submerged_weight_per_length(scene) -> float:
    cable = scene.cable
    return (cable.density - WATER) * np.pi * cable.diameter**2 / 4 * GRAVITY


def test_split_keeps_every_point_and_the_bonds():
    scene = line_scene({})
    models = LineModels(spec_from_scene(scene), 10.0, compiled=False)
    before, after = models.model(4), models.model(5)
    u = np.zeros(15)
    u[INPUTS.top_length], u[INPUTS.top_length_rate] = 17.0, 0.4
    psi = np.pi / 2 + np.array([0.05, 0.04, -0.02, 0.03, 0.1])
    state = chained_state(before, u, psi, [0.01, -0.02, 0.0, 0.02, 0.03])
    size = state.size // 2
    state[size + 3 :: 5] = [0.01, -0.02, 0.03, 0.02, 0.05]  # psi rates
    state[size + 4 :: 5] = [0.0, 0.01, -0.01, 0.02, -0.03]  # theta rates
    # Joint velocities that keep the bonds' rates: chained up from A_0 at rest.
    q, qd = state[:size].reshape(-1, 5), state[size:].reshape(-1, 5)
    lengths = [5.0, 10.0, 10.0, 10.0]
    for i in range(1, 5):
        qd[i, :3] = qd[i - 1, :3] + lengths[i - 1] * axis_rate(*q[i - 1, 3:5], *qd[i - 1, 3:5])
    top_velocity = (
        qd[4, :3]
        + 17.0 * axis_rate(*q[4, 3:5], *qd[4, 3:5])
        + 0.4
        * np.array(
            [np.cos(q[4, 4]) * np.cos(q[4, 3]), np.sin(q[4, 4]), np.cos(q[4, 4]) * np.sin(q[4, 3])]
        )
    )
    u[INPUTS.top_velocity] = top_velocity
    state = np.concatenate([q.ravel(), qd.ravel()])
    mapped = split(state, 4, 10.0)
    u_after = u.copy()
    u_after[INPUTS.top_length] = 7.0
    out_before = before.output_values(state, u)
    out_after = after.output_values(mapped, u_after)
    assert np.abs(out_before["bond_residual"]).max() < 1e-12
    assert np.abs(out_after["bond_residual"]).max() < 1e-12
    assert np.abs(out_after["bond_rate"]).max() < 1e-12
    # The new joint is the old rod's point Delta above A_n, moving as that point moved.
    np.testing.assert_allclose(out_after["joints"][:, :5], out_before["joints"][:, :5], atol=1e-12)
    p_before, m_before = momentum(state, np.array([5.0, 10, 10, 10, 17]), 31.0)
    p_after, m_after = momentum(mapped, np.array([5.0, 10, 10, 10, 10, 7]), 31.0)
    assert m_after == pytest.approx(m_before, rel=1e-15)
    np.testing.assert_allclose(p_after, p_before, atol=1e-12 * np.abs(p_before).max())


def test_axis_rate_is_the_derivative_of_the_axis():
    from conftest import axis

    psi, theta, d_psi, d_theta, h = 1.3, 0.2, 0.7, -0.4, 1e-6
    numeric = (
        axis(psi + h * d_psi, theta + h * d_theta) - axis(psi - h * d_psi, theta - h * d_theta)
    ) / (2 * h)
    np.testing.assert_allclose(axis_rate(psi, theta, d_psi, d_theta), numeric, atol=1e-9)


def test_merge_holds_the_bonds_and_moves_the_rope_by_the_chord_excess():
    scene = line_scene({})
    models = LineModels(spec_from_scene(scene), 10.0, compiled=False)
    before, after = models.model(5), models.model(4)
    u = np.zeros(15)
    u[INPUTS.top_length] = 4.0
    kink = 0.02
    psi = np.pi / 2 + np.array([0.0, 0.0, 0.0, 0.0, 0.0, kink])
    state = chained_state(before, u, psi, 0.0)
    mapped = merge(state, 5, 10.0, 4.0, u[INPUTS.top], u[INPUTS.top_velocity], 0.0)
    u_after = u.copy()
    u_after[INPUTS.top_length] = 14.0
    out = after.output_values(mapped, u_after)
    assert np.abs(out["bond_residual"]).max() < 1e-12
    assert np.abs(out["bond_rate"]).max() < 1e-12
    # A straight rod is longer than the kinked pair's chord by Delta l alpha^2 / (2 (Delta + l)).
    excess = 10.0 * 4.0 * kink**2 / (2 * 14.0)
    moved = np.linalg.norm(mapped[:3] - state[:3])
    assert moved == pytest.approx(excess, rel=0.01)


def test_mass_follows_the_drum_through_splits_and_merges(validation):
    """Acceptance 1: the rope's mass is mu L_out(t) at every output; the bonds hold."""
    scene = line_scene(
        {
            "top.motion": "tow",
            "cable.length": 60.0,
            "numerics.duration": 60.0,
            "numerics.step": 0.05,
            "environment.current": [0.3, 0.1, 0.0],
        },
        pay_out_max=60.0,
        haul_in_max=10.0,
    )
    radius = scene.winch.drum_radius
    angle = ramped_pay_out(2.0, 5.0, radius, reverse_at=30.0)
    run = co.simulate(scene, winch=angle, compiled=True)
    counts = run.element_count
    assert np.any(np.diff(counts) > 0) and np.any(np.diff(counts) < 0)
    mu = scene.cable.density * np.pi * scene.cable.diameter**2 / 4
    expected = mu * (scene.cable.length + radius * (run.winch_angle - run.winch_angle[0]))
    modelled = np.concatenate(
        [mu * run.element_lengths(k).sum(axis=1)[:-1] for k in range(len(run.segments) - 1)]
        + [mu * run.element_lengths(len(run.segments) - 1).sum(axis=1)]
    )
    error = float(np.abs(modelled / expected - 1).max())
    changes = int(np.abs(np.diff(counts)).sum())
    validation(
        f"tow and current, 60 m -> 115 m -> 60 m at 2 m/s, 10 m elements ({changes} splits "
        "and merges)",
        "conservation",
        "mu L_out(t), L_out from the drum's angle",
        "rope mass, largest relative error; largest bond residual",
        f"{error:.1e}; {run.bond_residual:.1e} m",
        f"<= 1e-12; <= {scene.numerics.constraint_tolerance:g} m (numerics.constraint_tolerance)",
    )
    assert error <= 1e-12
    assert run.bond_residual <= scene.numerics.constraint_tolerance


def test_quasi_static_pay_out_follows_the_line_and_its_weight(validation):
    """Acceptance 2 (short): a vertical rope with 2 t in still water paid out from 50 m."""
    scene = line_scene(
        {"cable.length": 50.0, "numerics.duration": 300.0, "numerics.step": 0.05},
        pay_out_max=70.0,
    )
    run = co.simulate(scene, winch=ramped_pay_out(0.2, 10.0, 0.5), compiled=True)
    settled = run.time > 60.0
    line = scene.cable.length + 0.5 * (run.winch_angle - run.winch_angle[0])
    depth_error = run.end[:, 2] - (run.top[:, 2] - line)
    weight = (PAYLOAD["mass"] - WATER * PAYLOAD["volume"]) * GRAVITY
    static = weight + submerged_weight_per_length(scene) * line
    depth = float(np.abs(depth_error[settled]).max())
    tension = float(np.abs(run.top_tension[settled] / static[settled] - 1).max())
    validation(
        f"vertical rope, 2 t payload, still water, 0.2 m/s from 50 m to {line[-1]:.0f} m, "
        f"10 m elements ({len(run.segments)} segments), after 60 s",
        "analytic",
        "z_top - L_out(t); submerged weight of payload and line out",
        "end depth error; top tension relative error",
        f"{depth:.1e} m; {tension:.1e}",
        "< 1 cm; < 0.5 %",
    )
    assert depth < 0.01
    assert tension < 0.005
    assert len(run.segments) > 3


def test_a_graded_top_element_is_not_paid_out_into_a_rod():
    scene = co.load_scene(MODELS / "paper_hill.toml", {"winch.angle_max": 600.0})
    knots = np.linspace(0, 400.0, scene.winch.knots)
    with pytest.raises(ValueError, match="rigid rod"):
        co.simulate(scene, winch=knots)


@pytest.mark.parametrize(
    ("overrides", "field"),
    [
        ({"winch.line": {"haul_in_max": 290.0}}, "winch.line.haul_in_max"),
        ({"winch.line": {"pay_out_max": 1e5}}, "winch.line.pay_out_max"),
        ({"winch.line": {"haul_in_max": 5.0}, "winch.angle_min": -2.0}, "winch.angle_min"),
        ({"winch.line": {"element_length": -1.0}}, "winch.line.element_length"),
    ],
)
def test_a_line_it_cannot_follow_is_refused(overrides, field):
    with pytest.raises(ValueError, match=field.replace(".", r"\.")):
        co.load_scene(MODELS / "paper_flat.toml", overrides)


def test_the_drum_beyond_its_metres_is_refused_before_integrating():
    scene = line_scene({"cable.length": 50.0, "numerics.duration": 20.0}, pay_out_max=1.0)
    with pytest.raises(ValueError, match="winch.line.pay_out_max"):
        co.simulate(scene, winch=ramped_pay_out(0.5, 2.0, 0.5))


@pytest.fixture(scope="module")
def short_run():
    """50 m -> 66 m at 0.6 m/s: three segments."""
    scene = line_scene(
        {"cable.length": 50.0, "numerics.duration": 30.0, "numerics.step": 0.05},
        pay_out_max=20.0,
    )
    return co.simulate(scene, winch=ramped_pay_out(0.6, 2.0, 0.5), compiled=True)


def test_a_line_run_round_trips_through_netcdf(tmp_path, short_run):
    run = short_run
    assert len(run.segments) >= 2
    loaded = LineTrajectory.load(run.save(tmp_path / "line"))
    assert len(loaded.segments) == len(run.segments)
    assert all(a.equals(b) for a, b in zip(run.segments, loaded.segments, strict=True))
    np.testing.assert_array_equal(loaded.element_count, run.element_count)


def test_the_whole_run_views_take_each_instant_once(short_run):
    run = short_run
    assert np.all(np.diff(run.time) > 0)
    assert run.joints.shape == (run.time.size, 3, run.element_count.max() + 2)
    first = run.segments[0]
    k = first.time.size - 1  # the change: the state after it, with one more joint
    assert np.isnan(run.joints[k - 1, 0, -1]) and np.isfinite(run.joints[k, 0, -1])
    np.testing.assert_array_equal(run.end[:k], first.end[:-1])


def test_a_line_run_is_plotted_and_animated_with_its_element_count(tmp_path, short_run):
    from cable_ocp import plots

    plots.line_run(short_run, path=tmp_path / "line.png")
    animation = plots.animate(short_run, path=tmp_path / "line.gif", frames=4)
    assert (tmp_path / "line.png").stat().st_size > 0
    assert (tmp_path / "line.gif").stat().st_size > 0
    label = animation._func(short_run.time.size - 1)[-1]
    assert label.get_text().endswith(f"n = {short_run.element_count[-1]}")


# ----------------------------------------------------------------------------------------------
# Long validation runs (-m slow): the acceptance 2-4 and 6.


@pytest.mark.slow
def test_quasi_static_pay_out_from_50_m_to_1000_m(validation):
    """Acceptance 2: 2 t in still water, 0.2 m/s from 50 m to 1000 m, 10 m elements."""
    duration = 5.0 + 950.0 / 0.2  # the ramp's half and the steady pay-out
    scene = line_scene(
        {
            "cable.length": 50.0,
            "numerics.duration": duration,
            "numerics.step": 0.05,
            "numerics.output_every": 20,
        },
        pay_out_max=951.0,
    )
    run = co.simulate(scene, winch=ramped_pay_out(0.2, 10.0, 0.5), compiled=True)
    settled = run.time > 60.0
    line = scene.cable.length + 0.5 * (run.winch_angle - run.winch_angle[0])
    depth = float(np.abs(run.end[:, 2] - (run.top[:, 2] - line))[settled].max())
    static = pv.static_top_tension(scene, line)
    tension = float(np.abs(run.top_tension / static - 1)[settled].max())
    validation(
        f"vertical rope, 2 t payload, still water, 0.2 m/s from 50 m to {line[-1]:.0f} m, "
        f"10 m elements (n = {run.element_count.min()}..{run.element_count.max()}), after 60 s",
        "analytic",
        "z_top - L_out(t); submerged weight of payload and line out",
        "end depth error; top tension relative error (the axial drag at 0.2 m/s: 0.2 %)",
        f"{depth:.1e} m; {tension:.1e}",
        "< 1 cm; < 0.5 %",
    )
    assert depth < 0.01
    assert tension < 0.005


CONVERGENCE_LENGTHS = (20.0, 10.0, 5.0, 2.5)


def _converges(validation, start: float, change: float, what: str) -> pv.Convergence:
    result = pv.convergence(start, change, CONVERGENCE_LENGTHS, speed=2.0)
    differences = ", ".join(f"{d * 100:.2g}" for d in result.differences)
    validation(
        f"{what} {start:.0f} m -> {start + change:.0f} m at 2 m/s under the tow and a sheared "
        f"current, 2 t payload, Delta = 20, 10, 5, 2.5 m ({result.changes} changes at 2.5 m)",
        "converged reference",
        "the same run at Delta = 2.5 m",
        "largest end distance at Delta = 20, 10, 5 m; observed order (10 vs 5)",
        f"{differences} cm; {result.order:.2f}",
        "falls with Delta; order > 1.5; finest two < 5 cm",
    )
    assert np.all(np.diff(result.differences) < 0)
    assert result.order > 1.5
    assert result.finest_two < 0.05
    return result


@pytest.mark.slow
def test_pay_out_under_tow_converges_in_the_element_length(validation):
    """Acceptance 3: 100 m -> 800 m under the tow and a sheared current."""
    _converges(validation, 100.0, 700.0, "pay-out")


@pytest.mark.slow
def test_haul_in_under_tow_converges_as_the_pay_out(validation):
    """Acceptance 6 (convergence): the reverse of acceptance 3, 800 m -> 100 m."""
    _converges(validation, 800.0, -700.0, "haul-in")


@pytest.fixture(scope="module")
def insertion_transients():
    """Acceptance 4's runs: 0.5 m/s from 100 m to 200 m, the shortest top 5 cm."""
    runs, finest = pv.insertion_runs()
    return runs, finest, {d: pv.transient(run, finest) for d, run in runs.items()}


@pytest.mark.slow
def test_insertion_transient_is_under_one_percent(validation, insertion_transients, tmp_path):
    """Acceptance 4: the top tension's jump at a split, against the finest run (1.25 m); the
    figure of the runs (``cable-ocp study payout`` writes it too)."""
    runs, finest, rows = insertion_transients
    fig = pv.transient_chart(runs, finest, tmp_path / "payout_transients.png")
    assert (tmp_path / "payout_transients.png").stat().st_size > 10_000
    assert len(fig.axes[0].get_legend().get_texts()) == len(runs) + 2
    figures = "; ".join(
        f"new top {t.new_top_length:.2g} m: {t.jump:.1e}, {t.against_finest:.1e}"
        for t in rows.values()
    )
    validation(
        "pay-out at 0.5 m/s from 100 m to 200 m under the tow and a sheared current, "
        "Delta = 10, 5, 2.5 m (top after a split l_min + Delta/2, l_min = 5 cm)",
        "converged reference",
        "the static top tension; the same run at Delta = 1.25 m",
        "largest top tension jump at a split; its change against the finest run (relative)",
        figures,
        "< 1 % each",
    )
    for t in rows.values():
        assert t.changes > 5
        assert t.jump < 0.01
        assert t.against_finest < 0.01


@pytest.mark.slow
def test_merging_makes_no_larger_transient_than_splitting(validation, insertion_transients):
    """Acceptance 6 (transient): 200 m -> 100 m at 0.5 m/s, against acceptance 4's splits."""
    # The top shrinks to l_min before a merge: at 5 cm the RK4 step of 0.004 s/m * Delta blew
    # up (a stiff short pendulum); the default l_min = Delta / 2 holds.
    splits = insertion_transients[2]
    fine = pv.tow_run(200.0, -100.0, pv.FINEST_TRANSIENT, 0.5)
    merges = {
        d: pv.transient(pv.tow_run(200.0, -100.0, d, 0.5), fine) for d in pv.TRANSIENT_LENGTHS
    }
    figures = "; ".join(
        f"Delta {d:g} m: {t.jump:.1e}, {t.against_finest:.1e} (splits {splits[d].jump:.1e})"
        for d, t in merges.items()
    )
    validation(
        "haul-in at 0.5 m/s from 200 m to 100 m under the tow and a sheared current, "
        "Delta = 10, 5, 2.5 m (l_min = Delta/2; at 5 cm the short top blew RK4 up)",
        "converged reference",
        "the splits of the reverse pay-out; the same run at Delta = 1.25 m",
        "largest top tension jump at a merge; its change against the finest run (relative)",
        figures,
        "<= the pay-out's at the same Delta; < 1 %",
    )
    for d, t in merges.items():
        assert t.changes > 5
        assert t.jump <= splits[d].jump
        assert t.against_finest < 0.01


def test_outputs_too_far_apart_for_the_pay_out_are_refused_before_integrating():
    scene = line_scene(
        {"cable.length": 50.0, "numerics.duration": 20.0, "numerics.output_every": 100},
        pay_out_max=20.0,
    )  # 5 s between outputs at 0.6 m/s: 3 m, more than half the shortest top element (5 m)
    with pytest.raises(ValueError, match="numerics.output_every = 100"):
        co.simulate(scene, winch=ramped_pay_out(0.6, 2.0, 0.5))


@pytest.mark.slow
def test_pay_out_agrees_with_moordyn(validation):
    """Acceptance 5: MoorDyn's rescaled line against the split-off elements, N = 100."""
    pytest.importorskip("moordyn")
    from cable_ocp.studies import moordyn_payout

    result = moordyn_payout.compare(start=100.0, pay_out=200.0, elements=100, speed=1.0)
    assert np.all(np.isfinite(result.moordyn))
    moved = float(np.linalg.norm(result.cable_ocp[-1] - result.cable_ocp[0]))
    validation(
        "paper_flat's tow, 100 m -> 300 m at 1 m/s (cable_ocp 3 m elements, n = "
        f"{result.elements[0]} -> {result.elements[1]}; MoorDyn N = 100 segments of L(t)/100)",
        "peer code",
        "MoorDyn 2 (lumped mass, extensible; SetLineUnstretchedLength/Vel every 1 ms), RK4 at "
        "2e-4 s",
        "largest end distance over the run, as a share of the line paid out",
        f"{result.difference:.3f} m = {result.share:.2%} (the end moved {moved:.0f} m)",
        "< 0.5 %",
    )
    assert moved > 100.0
    assert result.share < 0.005


@pytest.mark.parametrize("elements", [2, 7, 70])
def test_the_models_of_every_n_match_the_flat_model_on_one_library(elements):
    """The compiled kernels in blocks (70 = 64 + 4 + 1 + 1) give the flat model's x'."""
    from cable_ocp.model import structured
    from cable_ocp.model.cable import CableModel
    from cable_ocp.model.line_models import line_spec

    scene = line_scene({"environment.current": [0.4, 0.1, 0.0]})
    models = LineModels(spec_from_scene(scene), 10.0, compiled=True)
    model = models.model(elements)
    flat = CableModel(line_spec(spec_from_scene(scene), elements, 10.0))
    rng = np.random.default_rng(elements)
    u = np.zeros(15)
    u[INPUTS.top_length], u[INPUTS.top_length_rate] = 7.0, 0.3
    state = chained_state(model, u, np.pi / 2 + 0.05 * rng.standard_normal(elements + 1), 0.02)
    state[state.size // 2 :] = 0.05 * rng.standard_normal(state.size // 2)
    compiled = model.bind(structured.compiled_library(model.parametric, "rhs")[0])
    ours = np.array(compiled(state, u)).ravel()
    reference = np.array(flat.rhs(state, u)).ravel()
    np.testing.assert_allclose(ours, reference, rtol=0, atol=1e-12 * np.abs(reference).max())


def test_the_command_line_simulates_a_line_and_draws_its_element_count(tmp_path, capsys):
    from cable_ocp import cli

    scene = tmp_path / "lowering.toml"
    scene.write_text(
        "[model]\n[numerics]\nduration = 28.0\nstep = 0.05\nconstraint_tolerance = 1e-4\n"
        "[top]\nmotion = 'fixed'\n[cable]\nlength = 50.0\n[end.payload]\nmass = 2000.0\n"
        "volume = 0.256\n[winch]\nknots = 4\n[winch.line]\npay_out_max = 30.0\n"
    )
    out = tmp_path / "out"
    knots = "10,20,30,40"  # rad on r_D = 0.5 m: 20 m paid out over 28 s
    assert cli.main(["simulate", str(scene), "--out", str(out), "--quiet", "--knots", knots]) == 0
    assert (out / "line_run.png").stat().st_size > 1000
    run = LineTrajectory.load(out / "trajectory")
    assert run.line_out[-1] == pytest.approx(70.0, abs=1e-9)
    assert run.element_count[-1] > run.element_count[0]
    capsys.readouterr()


def test_the_bench_prints_the_pay_out_beside_the_fixed_n_model(capsys):
    from cable_ocp.studies import bench_payout

    rows = bench_payout.report(MODELS, quick=True)
    out = capsys.readouterr().out
    assert "variable n (split/merge, shared kernels)" in out and "fixed n = 24" in out
    assert rows["line_real_time"] > 1.0 and rows["fixed_real_time"] > 1.0


def test_a_survey_site_pays_out_over_its_grid_in_its_sea_state():
    """``survey`` (bathymetry grid, current profile, JONSWAP heave) with a line on the drum."""
    scene = co.load_scene(
        MODELS / "survey.toml",
        {"numerics.duration": 60.0, "winch.line": {"pay_out_max": 30.0, "element_length": 10.0}},
    )
    run = co.simulate(scene, winch=ramped_pay_out(0.5, 5.0, scene.winch.drum_radius))
    assert run.element_count[-1] > run.element_count[0]
    expected = scene.cable.length + 0.5 * (run.time - 2.5)  # after the ramp's half
    settled = run.time > 5.0
    np.testing.assert_allclose(run.line_out[settled], expected[settled], atol=1e-9)
    assert run.bond_residual <= scene.numerics.constraint_tolerance
    assert np.isfinite(run.omega)


def test_outputs_that_cannot_fit_in_memory_are_refused_before_integrating(monkeypatch):
    from cable_ocp.simulation import budget

    monkeypatch.setattr(budget, "available_memory", lambda: 10**6)  # 1 MB
    scene = line_scene({"cable.length": 50.0, "numerics.duration": 300.0}, pay_out_max=100.0)
    with pytest.raises(ValueError, match="over the limit of 0.0008 GB"):
        co.simulate(scene, winch=ramped_pay_out(0.3, 5.0, 0.5))


def test_optimize_and_mpc_refuse_a_line_paid_out_by_elements_by_name():
    """The winch problem keeps one model of fixed n: a [winch.line] scene is refused before any
    work, naming the section, instead of failing inside a transcription."""
    scene = line_scene({"numerics.duration": 20.0})
    with pytest.raises(ValueError, match=r"winch.line: optimize works on a fixed number"):
        co.optimize(scene, quiet=True)
    with pytest.raises(ValueError, match=r"winch.line: mpc works on a fixed number"):
        co.mpc(scene, quiet=True)
