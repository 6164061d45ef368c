"""The ocp-speed benchmark part: its figures and its command line (no wall-clock assertions)."""

from __future__ import annotations

from cable_ocp.cli import build_parser
from cable_ocp.studies import bench


def test_ocp_speed_case_reports_a_verified_solve(models_dir):
    """The quick case (small_tow) converges, holds its bounds and splits its wall time."""
    figures = bench.ocp_speed_case(str(models_dir / "small_tow.toml"), "gauss-newton", quick=True)
    assert figures["success"] and figures["bounds_held"]
    assert figures["omega"] < 1e-3  # measured 2.2e-4 m
    parts = ("build", "compile", "solve", "verification")
    assert all(figures[k] >= 0.0 for k in parts)
    assert sum(figures[k] for k in parts) <= figures["wall"]


def test_bench_accepts_the_ocp_speed_and_mpc_parts():
    args = build_parser().parse_args(["bench", "--only", "mpc", "ocp-speed", "--quick"])
    assert args.only == ["mpc", "ocp-speed"] and args.quick


def test_bench_writes_its_figure_only_into_out(tmp_path, monkeypatch, capsys):
    """``bench --only mpc``: without ``--out`` nothing lands in the working directory; with it,
    the solve-time figure is in that folder."""
    from cable_ocp import cli
    from cable_ocp.plots import closed_loop
    from cable_ocp.studies import bench_mpc

    drawn = []
    monkeypatch.setattr(bench_mpc, "report", lambda models, quick: ["results"])
    monkeypatch.setattr(
        closed_loop,
        "solve_time_comparison",
        lambda results, path, scene_name: drawn.append(path) or path.write_bytes(b"png"),
    )
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    assert cli.main(["bench", "--only", "mpc"]) == 0
    assert not drawn and list(work.iterdir()) == []
    assert "not written (give --out DIR)" in capsys.readouterr().out
    assert cli.main(["bench", "--only", "mpc", "--out", str(tmp_path / "figures")]) == 0
    assert (tmp_path / "figures" / "mpc_solve_times.png").read_bytes() == b"png"
    assert list(work.iterdir()) == []


def test_ocp_speed_report_runs_the_default_solver_cold_then_warm_against_ipopt(
    models_dir, monkeypatch, capsys
):
    """Each solver runs cold then warm on one cache of its own; IPOPT is the baseline."""
    from cable_ocp.control.solvers import DEFAULT_SOLVER, SOLVERS

    calls = []

    def process(scene_path, solver, quick, cache):
        calls.append((solver, cache))
        wall = 2.0 if solver == DEFAULT_SOLVER else 4.0  # the default twice as fast
        figures = dict.fromkeys(("build", "compile", "solve", "verification"), 0.1)
        return {**figures, "wall": wall, "process": wall + 1, "iterations": 3, "solves": 1,
                "omega": 1e-4, "success": True, "bounds_held": True}  # fmt: skip

    monkeypatch.setattr(bench, "_ocp_speed_process", process)
    rows = bench.ocp_speed_report(models_dir, quick=True)
    default, ipopt = SOLVERS[DEFAULT_SOLVER].label, SOLVERS["ipopt"].label
    assert [label for label, _ in rows] == [
        f"{default}, cold",
        f"{default}, warm",
        f"{ipopt} L-BFGS, cold",
        f"{ipopt} L-BFGS, warm",
    ]
    assert [solver for solver, _ in calls] == [DEFAULT_SOLVER] * 2 + ["ipopt"] * 2
    assert calls[0][1] == calls[1][1] != calls[2][1] == calls[3][1]
    printed = capsys.readouterr().out
    assert printed.count("2.0x") == 2 and printed.count("1.0x") == 2


def test_qp_bench_solves_each_qp_of_a_solve_both_ways_to_the_same_step(capsys):
    """``bench --only qp --quick`` (paper_hill's first Gauss-Newton solve): every QP is timed
    screened and whole, the two steps agree to the QP's margin, and the table is printed."""
    from cable_ocp.control.gauss_newton import QP_MARGIN
    from cable_ocp.studies import bench_qp

    timings = bench_qp.report(quick=True)["paper_hill"]
    assert len(timings) >= 2  # a step and the QP that finds nothing left to gain
    for timing in timings:
        assert timing.rows > timing.near >= 0 and timing.parameters == 84
        assert timing.screened > 0 and timing.whole > 0
        assert timing.difference <= QP_MARGIN
    assert "screened against" in capsys.readouterr().out
    assert build_parser().parse_args(["bench", "--only", "qp"]).only == ["qp"]


def test_bench_runs_blas_on_one_thread_unless_told_otherwise():
    """``cable-ocp bench`` sets the BLAS thread counts the user left unset; other commands not."""
    from cable_ocp.entry import BLAS_THREADS, one_blas_thread_for_bench

    environ = {"OMP_NUM_THREADS": "2"}
    one_blas_thread_for_bench(["bench", "--only", "grid"], environ)
    assert environ == {**dict.fromkeys(BLAS_THREADS, "1"), "OMP_NUM_THREADS": "2"}
    untouched: dict[str, str] = {}
    one_blas_thread_for_bench(["optimize", "models/paper_hill.toml"], untouched)
    one_blas_thread_for_bench([], untouched)
    assert untouched == {}
