"""What a newcomer meets first on the command line (issue 45 item 10): the top-level help names
every command, ``bench --help`` says what it runs and how long, ``--knots`` says where the knots
sit, and a mistyped scene name gets the closest bundled names."""

from __future__ import annotations

import pytest

from cable_ocp import cli
from cable_ocp.scene.bundled import closest_names, scene_path


def _help(capsys, *command: str) -> str:
    assert cli.main([*command, "--help"]) == 0
    return " ".join(capsys.readouterr().out.split())


def _commands() -> list[str]:
    parser = cli.build_parser()
    (subparsers,) = [a for a in parser._actions if a.dest == "command"]
    return list(subparsers.choices)


def test_the_top_level_help_names_every_command(capsys):
    text = _help(capsys)
    described = text.split("Commands:", 1)[1].split("Every expected failure", 1)[0]
    words = {word.strip(",;.") for word in described.split()}
    assert "replay" in _commands() and set(_commands()) <= words


def test_bench_help_says_what_it_runs_and_how_long(capsys):
    text = _help(capsys, "bench")
    assert "tens of minutes on 2 cores" in text and "--quick runs short versions" in text
    assert "10 cases took 5 min" in text


def test_the_knots_help_says_where_the_knots_sit(capsys):
    text = _help(capsys, "simulate")
    assert "phi(0) = 0 is put before them, knot i sits at t = i T / p" in text
    assert "starts at rest (zero rate; free at the end)" in text


@pytest.mark.parametrize(
    ("typed", "meant"), [("paper_hil", "paper_hill"), ("smal_tow", "small_tow")]
)
def test_a_mistyped_scene_name_gets_the_closest_bundled_ones(tmp_path, capsys, typed, meant):
    code = cli.main(["simulate", typed, "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert code == 2 and f"did you mean {meant}" in err and "cable-ocp scenes lists" in err
    assert closest_names(typed)[0] == meant
    with pytest.raises(ValueError, match=f"is not a bundled scene \\(did you mean {meant}"):
        scene_path(typed)


def test_a_name_far_from_every_scene_is_a_missing_file(tmp_path, capsys):
    assert closest_names("zzz_unrelated") == []
    code = cli.main(["simulate", "zzz_unrelated", "--out", str(tmp_path / "o")])
    assert code == 2 and "not found" in capsys.readouterr().err


def test_the_printed_times_say_whose_they_are(tmp_path, capsys):
    """The 'wall' printed was optimize()'s (1.4 s) for a command of 7.8 s: both, each named."""
    import re

    from conftest import MODELS

    args = ["optimize", str(MODELS / "small_tow.toml"), "--intervals", "8", "--quiet"]
    assert cli.main([*args, "--out", str(tmp_path / "o")]) == 0
    out = capsys.readouterr().out
    found = re.search(r"optimize\(\) took ([\d.]+) s .*, the whole command ([\d.]+) s \(with", out)
    assert found, out
    assert float(found[2]) > float(found[1])
