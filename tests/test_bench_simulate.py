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
