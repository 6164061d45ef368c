"""Figures and messages read right: titles name the scene and the run, numbers have significant
digits, axes have units, the validate table is in order with units; progress counts whole steps
and keeps out of other output; a finished sweep leaves no lock (issue 28)."""

from __future__ import annotations

import dataclasses
import fcntl
import io
import re

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

import cable_ocp as co  # noqa: E402
from cable_ocp import cli, plots  # noqa: E402
from cable_ocp.control.closed_loop import SolveLog  # noqa: E402
from cable_ocp.plots import closed_loop  # noqa: E402
from cable_ocp.plots.drum_limits import drum_use  # noqa: E402
from cable_ocp.plots.tension import tension_against_static  # noqa: E402
from cable_ocp.simulation import progress  # noqa: E402
from cable_ocp.simulation.trajectory_dataset import state_names  # noqa: E402

UNIT = re.compile(r"\[[^\]]+\]")  # "x [m]", "t [s]", "winch angle phi [rad]"


@pytest.fixture(scope="module")
def runs(models_dir):
    """A short locked run renamed paper_hill with the optimum's Omega, and a moving-winch twin."""
    scene = co.load_scene(models_dir / "hanging.toml",
                          {"numerics.duration": 4.0, "model.elements": 5})  # fmt: skip
    locked = dataclasses.replace(co.simulate(scene, quiet=True), scene_name="paper_hill",
                                 omega=4.2762)  # fmt: skip
    moving = dataclasses.replace(locked, omega=1.302e-4,
                                 winch_angle=0.5 * np.sin(locked.time))  # fmt: skip
    return locked, moving


def legend_texts(ax) -> list[str]:
    legend = ax.get_legend()
    return [] if legend is None else [t.get_text() for t in legend.get_texts()]


def assert_units(ax):
    for label in (ax.get_xlabel(), ax.get_ylabel()):
        assert UNIT.search(label), f"axis label without a unit: {label!r}"


@pytest.mark.parametrize(
    ("value", "text"),
    [(1.302e-4, "1.30e-4"), (4.2762, "4.28"), (0.0234, "0.0234"), (12.0, "12.0"), (0.0, "0"),
     (-7.3e-6, "-7.30e-6"), (123456.0, "1.23e5"), (float("nan"), "nan")],
)  # fmt: skip
def test_numbers_have_three_significant_digits(value, text):
    assert plots.significant(value) == text


def test_the_clearance_legend_shows_a_small_omega_in_significant_digits(runs):
    fig = plots.clearance(runs, 5.0, ["locked winch", "optimised (ipopt)"])
    ax = fig.axes[0]
    texts = legend_texts(ax)
    assert "optimised (ipopt) (Omega = 1.30e-4 m)" in texts, texts
    assert "locked winch (Omega = 4.28 m)" in texts
    assert not any("0.000 m" in t for t in texts)
    assert "paper_hill" in ax.get_title() and "locked winch vs optimised (ipopt)" in ax.get_title()
    assert_units(ax)
    plt.close(fig)


def test_the_winch_angle_names_scene_run_and_its_dotted_bounds(runs):
    fig = plots.winch_angle(runs, ["locked winch", "optimised (ipopt)"], (-16.0, 24.0))
    ax = fig.axes[0]
    title = ax.get_title()
    assert "winch angle" in title and "paper_hill" in title and "optimised (ipopt)" in title
    texts = legend_texts(ax)
    assert "winch bounds phi_min = -16 rad, phi_max = 24 rad" in texts, texts
    dotted = [line for line in ax.get_lines() if line.get_linestyle() == ":"]
    assert len(dotted) == 2 and dotted[0].get_label().startswith("winch bounds")
    assert_units(ax)
    plt.close(fig)


def test_a_simulation_figure_without_labels_names_its_run(runs):
    locked, moving = runs
    fig = plots.winch_angle(locked, bounds=(-1.0, 1.0))
    assert fig.axes[0].get_title().endswith("scene paper_hill: winch locked")
    plt.close(fig)
    fig = plots.clearance(moving)
    assert fig.axes[0].get_title().endswith("scene paper_hill: winch profile")
    plt.close(fig)


def test_the_end_trajectory_and_the_cable_shapes_name_the_scene(runs):
    fig = plots.end_trajectory(runs, ["locked winch", "optimised (ipopt)"])
    assert "paper_hill" in fig.get_suptitle() and "optimised (ipopt)" in fig.get_suptitle()
    for ax in fig.axes:
        assert_units(ax)
    plt.close(fig)
    fig = plots.cable_shapes(runs[1], label="optimised (ipopt)")
    title = fig.axes[0].get_title()
    assert "paper_hill" in title and "optimised (ipopt)" in title
    assert_units(fig.axes[0])
    plt.close(fig)


def test_the_catenary_legend_covers_neither_the_curve_nor_a_tick_label():
    s = np.linspace(0, 1, 50)
    analytic = np.vstack([140 * s**1.3, 265 * s])
    fig = plots.catenary_comparison(analytic[:, ::3], analytic, scene_name="catenary", elements=15)
    ax = fig.axes[0]
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    legend = ax.get_legend().get_window_extent(renderer)
    assert not legend.overlaps(ax.get_window_extent(renderer))  # below the axes
    (x0, x1), (y0, y1) = sorted(ax.get_xlim()), sorted(ax.get_ylim())
    shown = [t for t in ax.get_xticklabels() if x0 <= t.get_position()[0] <= x1]
    shown += [t for t in ax.get_yticklabels() if y0 <= t.get_position()[1] <= y1]
    assert len(shown) > 4
    for tick in shown:
        assert not legend.overlaps(tick.get_window_extent(renderer)), tick.get_text()
    figure = fig.bbox
    for text in ax.get_legend().get_texts():  # "rfe model joints, n = 15" not clipped
        box = text.get_window_extent(renderer)
        assert figure.x0 <= box.x0 and box.x1 <= figure.x1 and figure.y0 <= box.y0, text
    assert "rfe model joints, n = 15" in legend_texts(ax)
    assert "scene catenary" in ax.get_title() and "n = 15" in ax.get_title()
    assert_units(ax)
    plt.close(fig)


def test_the_drum_figure_names_scene_runs_units_and_limits(runs, models_dir):
    locked, _ = runs
    winch = {**locked.scene_record["winch"], "rate_max": 2.0}
    limited = dataclasses.replace(locked, scene_record={**locked.scene_record, "winch": winch})
    fig = drum_use(limited, ["locked winch"])
    assert "paper_hill" in fig.axes[0].get_title() and "locked winch" in fig.axes[0].get_title()
    assert UNIT.search(fig.axes[0].get_ylabel())
    assert_units(fig.axes[1])  # the time axis is the lower panel's
    texts = legend_texts(fig.axes[0])
    assert "winch.rate_max = 2.00" in texts
    assert "locked winch: at or past the limit 0% of the time" in texts
    # No acceleration limit: none drawn, and the legend says so.
    assert legend_texts(fig.axes[1]) == ["locked winch", "winch.acceleration_max: none set"]
    plt.close(fig)
    # A closed loop's file of format 2 kept only the end and the top: refused, saying so.
    earlier = co.Trajectory.from_positions(locked.time, locked.end, locked.top,
                                           locked.winch_angle, locked.clearance_error,
                                           locked.omega, locked.scene_record)  # fmt: skip
    with pytest.raises(ValueError, match="holds no winch inputs at its steps"):
        drum_use(earlier)
    with pytest.raises(ValueError, match="holds no tensions"):
        tension_against_static(earlier)
    with pytest.raises(ValueError, match="str holds no run to draw"):
        drum_use([locked, "run.nc"])


def _run(t: np.ndarray, error: np.ndarray, omega: float) -> co.Trajectory:
    """A run of one element on paper_hill (its end and top only matter to the figures)."""
    k = t.size
    return co.Trajectory(
        time=t, states=np.zeros((k, 20)), inputs=np.zeros((k, 15)), joints=np.zeros((k, 3, 3)),
        tensions=np.zeros((k, 2)), winch_angle=np.sin(t), clearance_error=error, omega=omega,
        scene_name="paper_hill", state_names=state_names(2, 5),
    )  # fmt: skip


def mpc_result(omega: float = 0.0234) -> co.MpcResult:
    t = np.linspace(0, 20, 41)
    samples = np.arange(0, 20, 1.0)
    return co.MpcResult(
        trajectory=_run(t, 1e-3 * np.sin(t), omega), planned_angle=np.sin(t),
        solves=SolveLog(samples, np.full(samples.size, 5.6e-3),
                        np.ones(samples.size, dtype=int), ["ok"] * samples.size),
        failures=[], success=True, status="", iterations=samples.size, solve_time=0.112,
        limited_steps=0, projected_samples=0, angle_range=(-16.0, 24.0),
        real_time_factor=157.3, worst_solve_time=7.7e-3, wall_time=1.0, build_time=0.5,
        settings={"solver": "gauss-newton", "sample_s": 1.0},
    )  # fmt: skip


def test_the_closed_loop_figures_name_scene_and_run():
    """The closed loop is drawn by the open loop's functions, beside its locked reference."""
    result = mpc_result(1.302e-4)
    t = result.time
    locked = _run(t, 4.0 * np.sin(t), 4.3312)
    fig = co.plots.clearance([locked, result], labels=["locked", "closed loop (gauss-newton)"],
                             zoom=True)  # fmt: skip
    title = fig.axes[0].get_title()
    assert "paper_hill" in title and "closed loop (gauss-newton)" in title and "locked" in title
    assert "closed loop (gauss-newton) (Omega = 1.30e-4 m)" in legend_texts(fig.axes[0])
    assert "locked (Omega = 4.33 m)" in legend_texts(fig.axes[0])
    assert "locked (Omega = 4.33 m)" not in legend_texts(fig.axes[1])  # the zoom
    plt.close(fig)
    fig = co.plots.winch_angle(result, bounds=result.angle_range)
    assert "paper_hill" in fig.axes[0].get_title()
    texts = legend_texts(fig.axes[0])
    assert any(t.startswith("winch bounds phi_min") for t in texts)
    assert "closed loop (gauss-newton), planned" in texts
    assert_units(fig.axes[0])
    plt.close(fig)
    fig = closed_loop.solve_times(result, scene_name="paper_hill")
    title = fig.axes[0].get_title()
    assert "paper_hill" in title and "median 5.60 ms" in title and "factor 157" in title
    for ax in fig.axes:
        assert UNIT.search(ax.get_ylabel()), ax.get_ylabel()
    plt.close(fig)


def test_the_validate_table_is_in_ascending_n_with_units(capsys):
    assert cli.main(["validate", "--elements", "15", "5", "8"]) == 0
    out = capsys.readouterr().out.splitlines()
    header = next(line for line in out if line.lstrip().startswith("n "))
    for column in ("eps_x [%]", "eps_z [%]", "inextensible [%]", "top tension [%]"):
        assert column in header
    rows = [int(line.split()[0]) for line in out if re.match(r"\s+\d+\s", line)]
    assert rows == [5, 8, 15]


def test_the_top_level_help_has_no_restructuredtext_markup(capsys):
    assert cli.main(["--help"]) == 0
    assert "``" not in capsys.readouterr().out


@pytest.mark.parametrize("command", ["simulate", "validate", "optimize", "compare", "mpc",
                                     "sweep", "study", "bench", "scenes", "schema"])  # fmt: skip
def test_every_option_has_help_and_a_fixed_default_is_shown(command, capsys):
    parser = cli.build_parser()
    sub = next(a for a in parser._actions if a.dest == "command").choices[command]
    for action in sub._actions:
        assert action.help, f"{command} {action.option_strings or action.dest}: no help"
    text = sub.format_help()
    for action in sub._actions:
        if action.option_strings and action.default not in (None, False, [], "==SUPPRESS=="):
            name = action.option_strings[-1]
            shown = re.search(re.escape(name) + r".*?default", text, re.S)
            assert shown, f"{command} {name}: default {action.default!r} not in the help"


class Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_progress_counts_whole_steps_and_clears_itself(monkeypatch):
    stream = Terminal()
    monkeypatch.setattr("sys.stderr", stream)
    bar = progress.Progress("simulate", 210.0)
    bar.update(183.6)
    assert bar.bar.n == 183 and isinstance(bar.bar.n, int) and bar.bar.total == 210
    bar.bar.refresh()
    assert "183/210" in stream.getvalue() and "183.6" not in stream.getvalue()
    progress.IterationLog("ipopt").line(3, 1.3e-4, 1e-9)  # written above the bar
    bar.update(210.0)
    assert bar.bar.n == 210
    bar.close()
    written = stream.getvalue()
    assert re.search(r"\r +\ripopt iter    3 .*\n", written)  # the bar cleared, the line, \n
    assert re.search(r"\r +\r$", written)  # and the bar cleared when it closes


def test_progress_of_a_fraction_of_a_unit_still_counts_whole_units(monkeypatch):
    monkeypatch.setattr("sys.stderr", Terminal())
    bar = progress.Progress("simulate", 0.5)
    bar.update(0.25)
    assert (bar.bar.n, bar.bar.total) == (0, 1)
    bar.update(0.5)
    assert bar.bar.n == 1
    bar.close()


def test_a_log_gets_one_line_and_no_bar(monkeypatch):
    stream = io.StringIO()  # not a terminal: a log
    monkeypatch.setattr("sys.stderr", stream)
    bar = progress.Progress("simulate", 210.0)
    bar.update(100.4)
    progress.IterationLog("ipopt").line(3, 1.3e-4, 1e-9)
    bar.update(183.6)
    assert bar.bar is None
    bar.close()
    bar.close()  # once
    lines = stream.getvalue().splitlines(keepends=True)
    assert len(lines) == 2 and all(line.endswith("\n") for line in lines)
    assert lines[0].startswith("ipopt iter    3") and "\r" not in stream.getvalue()
    assert lines[1].startswith("simulate:  87% 183/210 [")


def test_a_finished_sweep_leaves_no_lock(tmp_path):
    from test_sweep import GRID, write

    from cable_ocp.sweep import load_sweep, run_sweep

    out = tmp_path / "out"
    out.mkdir()
    (out / ".sweep.lock").write_text("pid 1 on an old host\n")  # left by cable_ocp <= 0.3
    report = run_sweep(load_sweep(write(tmp_path, GRID)), out, workers=1, quiet=True,
                       processes=False)  # fmt: skip
    assert report is not None
    names = sorted(p.name for p in out.iterdir())
    assert ".sweep.lock" not in names and not any("lock" in n for n in names), names
    assert not any("lock" in p.name for p in tmp_path.iterdir())  # nor one beside the folder


def test_an_old_sweeps_lock_that_is_held_is_left_to_it(tmp_path):
    from cable_ocp.sweep.store import LOCK, folder_lock

    folder = tmp_path / "out"
    folder.mkdir()
    held = open(folder / LOCK, "w")  # noqa: SIM115 (held across the block)
    fcntl.flock(held, fcntl.LOCK_EX | fcntl.LOCK_NB)  # a running sweep of cable_ocp <= 0.3
    try:
        with folder_lock(folder):
            pass
        assert (folder / LOCK).exists()
    finally:
        held.close()
    with folder_lock(folder):
        pass
    assert not (folder / LOCK).exists()


# --- axes that read as what they show (issue 45 item 10) -----------------------------------------


def _tick_texts(ax, axis: str = "y") -> list[str]:
    ax.figure.canvas.draw()
    ticks = ax.get_yticklabels() if axis == "y" else ax.get_xticklabels()
    return [t.get_text().replace("\N{MINUS SIGN}", "-") for t in ticks if t.get_text()]


def test_the_iteration_count_of_one_a_solve_has_whole_ticks_from_zero():
    """One real-time iteration a solve drew a count axis of 0.96-1.04."""
    fig = closed_loop.solve_times(mpc_result(), scene_name="paper_hill")
    twin = fig.axes[1]
    assert twin.get_ylim()[0] == 0 and twin.get_ylim()[1] >= 1.5
    texts = _tick_texts(twin)
    assert texts and all(re.fullmatch(r"\d+", text) for text in texts), texts
    plt.close(fig)


def test_a_clearance_within_a_millimetre_shows_heights_without_an_offset():
    """An optimum's replay: the end within 0.6 mm of 5 m drew '+5' and ticks of 1e-4."""
    t = np.linspace(0, 60, 121)
    fig = plots.clearance(_run(t, 6e-4 * np.sin(t), 4e-4), 5.0)
    ax = fig.axes[0]
    texts = _tick_texts(ax)
    assert ax.yaxis.get_offset_text().get_text() == ""
    assert all(abs(float(text) - 5.0) < 0.01 for text in texts), texts
    plt.close(fig)


def test_the_landings_middle_panel_spans_its_content_and_its_legend_spares_the_heave(models_dir):
    """landing.png: the middle panel's axis ran over the whole 960 s for 120 s of content, and
    its legend sat over the vessel's heave."""
    from types import SimpleNamespace

    from cable_ocp.plots import landing

    scene = co.load_scene(
        models_dir / "paper_flat.toml",
        {"top.motion": "fixed", "cable.length": 100.0, "seabed.clearance": 95.0,
         "end.payload": {"mass": 2000.0, "volume": 0.256},
         "lowering": {"land_time": 200.0, "height": 5.0, "tension_min": 1e3},
         "numerics.duration": 230.0},
    )  # fmt: skip
    t = np.linspace(0.0, 230.0, 461)
    depth = -100.0 - 90.0 * np.clip(t / 200.0, 0, 1) + 0.01 * np.sin(t)
    heave = 1.5 * np.sin(2 * np.pi * t / 9.0)
    run = SimpleNamespace(
        scene=scene, scene_name="paper_flat", time=t, end=np.stack([0 * t, 0 * t, depth], 1),
        top=np.stack([0 * t, 0 * t, heave], 1), top_tension=np.full(t.size, 2e4),
    )  # fmt: skip
    fig = landing.landing(run, label="optimised", path=None)
    middle = fig.axes[1]
    assert middle.get_xlim() == pytest.approx((180.0, 230.0))
    sea = next(ax for ax in fig.axes if ax.get_ylabel().startswith("vessel heave"))
    legend = sea.get_legend()
    assert legend is not None and "vessel heave (right axis)" in legend_texts(sea)
    fig.canvas.draw()
    box = legend.get_window_extent()
    (line,) = sea.get_lines()
    points = sea.transData.transform(line.get_xydata())
    inside = [box.contains(x, y) for x, y in points]
    assert not np.any(inside)
    plt.close(fig)
