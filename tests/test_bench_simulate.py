"""The simulate benchmark part: its rows and its command line (no wall-clock assertions)."""

from __future__ import annotations

from cable_ocp.cli import build_parser
from cable_ocp.studies import bench_simulate


def test_simulate_report_times_each_part(models_dir, capsys):
    rows = bench_simulate.simulate_report(models_dir, quick=True)
    assert [row[0] for row in rows] == ["paper_flat.toml"]
    _, end_to_end, integration, uncached = rows[0]
    assert min(end_to_end, integration, uncached) > 0  # times, s (their ratios are not asserted)
    assert "paper_flat.toml" in capsys.readouterr().out


def test_bench_accepts_the_simulate_part():
    args = build_parser().parse_args(["bench", "--only", "simulate"])
    assert args.only == ["simulate"]


def test_command_report_times_the_command_against_interpreted(models_dir, monkeypatch, capsys):
    """The command part: a warm-up, the compiled default twice, --interpreted once (no timing)."""
    runs = []

    def fake(arguments):
        runs.append(arguments)
        return 10.0 if "--interpreted" in arguments else 2.0

    monkeypatch.setattr(bench_simulate, "_command_time", fake)
    assert bench_simulate.command_report(models_dir, quick=True) == (2.0, 10.0)
    assert [("--interpreted" in r) for r in runs] == [False, False, False, True]
    assert runs[0][0].endswith("end_force.toml")
    assert "5.0x" in capsys.readouterr().out
