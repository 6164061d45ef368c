"""The simulate benchmark part: its rows and its command line (no wall-clock assertions)."""

from __future__ import annotations

import pytest

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


OUTPUTS = (["end_trajectory.png", "summary.json", "trajectory.nc"], {"scene": "end_force",
           "omega": 22.6, "final_end_position": [107.5, -14.4, -267.3]})  # fmt: skip


def test_command_report_times_the_command_against_interpreted(models_dir, monkeypatch, capsys):
    """A warm-up, then the compiled default and --interpreted twice each in turns (no timing)."""
    runs = []

    def fake(arguments):
        runs.append(arguments)
        return (10.0 if "--interpreted" in arguments else 2.0), OUTPUTS

    monkeypatch.setattr(bench_simulate, "_command_time", fake)
    assert bench_simulate.command_report(models_dir, quick=True) == (2.0, 10.0)
    assert [("--interpreted" in r) for r in runs] == [False, False, True, False, True]
    assert runs[0][0].endswith("end_force.toml")
    out = capsys.readouterr().out
    assert "5.0x" in out
    assert "best of 2 each" in out and "summary.json, trajectory.nc" in out


def test_command_report_refuses_runs_that_wrote_different_outputs(models_dir, monkeypatch):
    files, summary = OUTPUTS
    other = (files, {**summary, "omega": 22.7})
    monkeypatch.setattr(
        bench_simulate,
        "_command_time",
        lambda arguments: (1.0, other if "--interpreted" in arguments else OUTPUTS),
    )
    with pytest.raises(RuntimeError, match="different outputs"):
        bench_simulate.command_report(models_dir, quick=True)


def test_same_outputs_compares_files_and_summary_to_rounding():
    files, summary = OUTPUTS
    rounded = {**summary, "omega": summary["omega"] * (1 + 1e-12)}
    assert bench_simulate._same_outputs(OUTPUTS, (files, rounded))
    assert not bench_simulate._same_outputs(OUTPUTS, (files[:-1], summary))
    assert not bench_simulate._same_outputs(OUTPUTS, (files, {**summary, "omega": 23.0}))
