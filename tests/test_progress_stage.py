"""One bar for a run of parts (issue 45 item 10): a line run integrates each segment of constant n
on its own, and a pipe got one ``simulate: 100% 10/10`` line per segment (up to 200), naming no
stage. Inside :func:`stage` the parts move one bar, named for the run; quiet prints nothing."""

from __future__ import annotations

from cable_ocp import cli
from cable_ocp.simulation.progress import Progress, stage


def _segments(count: int, length: float, label: str = "simulate") -> None:
    for _ in range(count):
        part = Progress(label, length)
        part.update(length / 2)
        part.update(length)
        part.close()


def test_the_parts_of_a_stage_move_its_one_bar(capsys):
    with stage("simulate deploy", 30.0):
        _segments(3, 10.0)
    lines = capsys.readouterr().err.splitlines()  # stderr is not a terminal: the log's lines
    assert len(lines) == 1 and lines[0].startswith("simulate deploy: 100% 30/30 ["), lines


def test_a_quiet_stage_quiets_its_parts(capsys):
    with stage("simulate deploy", 30.0, quiet=True):
        _segments(3, 10.0)
    assert capsys.readouterr().err == ""


def test_other_progress_inside_a_stage_and_parts_outside_keep_their_own_lines(capsys):
    with stage("simulate deploy", 10.0):
        _segments(1, 10.0)
        _segments(1, 4.0, label="nelder-mead")
    _segments(2, 5.0)
    lines = capsys.readouterr().err.splitlines()
    assert [line.split(":")[0] for line in lines] == [
        "nelder-mead", "simulate deploy", "simulate", "simulate"
    ]  # fmt: skip


def test_a_line_run_on_the_command_line_prints_one_line_for_the_run(tmp_path, capsys):
    scene = tmp_path / "line.toml"
    scene.write_text(
        "[model]\n[numerics]\nduration = 28.0\nstep = 0.05\nconstraint_tolerance = 1e-4\n"
        "[top]\nmotion = 'fixed'\n[cable]\nlength = 50.0\n[end.payload]\nmass = 2000.0\n"
        "volume = 0.256\n[winch]\nknots = 4\n[winch.line]\npay_out_max = 30.0\n"
    )
    args = ["simulate", str(scene), "--out", str(tmp_path / "out"), "--knots", "10,20,30,40"]
    assert cli.main(args) == 0
    lines = capsys.readouterr().err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("simulate line: 100% 28/28"), lines
    assert cli.main([*args, "--quiet"]) == 0
    assert capsys.readouterr().err == ""
