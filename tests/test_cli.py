"""The command line: bad input is one line on stderr and exit 2, before any heavy work."""

import json
import shutil
import stat
import subprocess
import sys
from pathlib import Path

import pytest

from cable_ocp import cli, optimization, simulation, studies, validation
from cable_ocp.output import MARKER

MODELS = Path(__file__).resolve().parent.parent / "models"
HANGING = str(MODELS / "hanging.toml")


@pytest.fixture
def no_heavy_work(monkeypatch):
    """Make every simulation, optimisation, validation and study fail the test if it starts."""

    def forbidden(*args, **kwargs):
        pytest.fail("bad input must be refused before any heavy work")

    for module, name in [(simulation, "simulate"), (optimization, "optimize"),
                         (validation, "catenary_check"), (studies, "step_halving"),
                         (studies, "element_convergence"), (studies, "end_positions")]:  # fmt: skip
        monkeypatch.setattr(module, name, forbidden)


def run_cli(args, capsys):
    """``cli.main(args)`` in-process: (exit code, stdout, stderr)."""
    code = cli.main([str(a) for a in args])
    out, err = capsys.readouterr()
    return code, out, err


# (arguments, a fragment of the message); the scene is HANGING where a scene is needed.
BAD_ARGUMENTS = [
    (["simulate", "missing.toml", "--out", "o"], "missing.toml: scene file not found"),
    (["simulate", MODELS, "--out", "o"], "is a folder, not a scene file"),
    (["simulate", HANGING, "--out", "o", "--knots", "nan"], "knot 1 = 'nan': must be finite"),
    (["simulate", HANGING, "--out", "o", "--knots", "a,b"], "knot 1 = 'a' is not a number"),
    (["simulate", HANGING, "--out", "o", "--knots", ""], "--knots: empty"),
    (["simulate", HANGING, "--out", "o", "--knots", "1,2"],
     "--knots: 2 angles given; the scene has winch.knots = 14"),
    (["simulate", HANGING, "--out", "o", "--set", "model.elements=1e400"],
     "model.elements: expected an integer, got float inf"),
    (["simulate", HANGING, "--out", "o", "--set", f"model.elements={10**400}"],
     "model.elements = 1000000"),
    (["simulate", HANGING, "--out", "o", "--set", "cable.length=1e400"],
     "cable.length = inf is out of range: must be finite"),
    (["simulate", HANGING, "--out", "o", "--set", "cable.density=500"],
     "cable.density = 500.0 is out of range: must be > environment.water_density = 1025.0"),
    (["simulate", HANGING, "--out", "o", "--set", "model.elements"], "expected KEY=VALUE"),
    (["validate", "--elements", "0"], "argument --elements: 0 is out of range: must be 1 to 1000"),
    (["validate", "--elements", "1e400"], "argument --elements: expected an integer"),
    (["optimize", HANGING, "--out", "o", "--step", "nan"], "argument --step: 'nan' is out of"),
    (["optimize", HANGING, "--out", "o", "--step", "1e400"], "argument --step: '1e400' is out"),
    (["optimize", HANGING, "--out", "o", "--intervals", "0"], "argument --intervals: 0 is out"),
    (["optimize", HANGING, "--out", "o", "--quiet", "--verbose"], "not allowed with argument"),
    (["compare", HANGING, "missing.toml", "--out", "o"], "missing.toml: scene file not found"),
    (["study", "step", "--out", "o"], "study step needs a scene file"),
    (["study", "stability", HANGING, "--out", "o"], "study stability takes no scene"),
]  # fmt: skip


@pytest.mark.parametrize(("args", "message"), BAD_ARGUMENTS, ids=lambda v: None)
def test_bad_input_is_one_line_and_exit_2(
    tmp_path, monkeypatch, capsys, no_heavy_work, args, message
):
    monkeypatch.chdir(tmp_path)
    code, out, err = run_cli(args, capsys)
    assert code == 2
    assert message in err
    assert f"cable-ocp {args[0]}: error: " in err and "Traceback" not in err + out
    assert err.strip().splitlines()[-1].startswith(f"cable-ocp {args[0]}: error: ")
    assert list(tmp_path.iterdir()) == []  # nothing written


@pytest.mark.parametrize("target", [".", "here", "file.txt"])
def test_out_that_would_delete_files_is_refused_before_simulating(
    tmp_path, monkeypatch, capsys, no_heavy_work, target
):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "file.txt").write_text("mine")
    (tmp_path / "here").mkdir()
    (tmp_path / "here" / "data.csv").write_text("1,2")
    code, _, err = run_cli(["simulate", HANGING, "--out", target], capsys)
    assert code == 2 and "nothing was written" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file.txt", "here"]
    assert (tmp_path / "here" / "data.csv").read_text() == "1,2"


def test_simulate_writes_a_marked_folder_and_replaces_it(tmp_path, capsys):
    out = tmp_path / "res"
    args = ["simulate", HANGING, "--out", out, "--set", "numerics.duration=2.0", "--quiet"]
    assert run_cli(args, capsys)[0] == 0
    assert (out / MARKER).is_file()
    assert stat.S_IMODE(out.stat().st_mode) & 0o055 == 0o055  # group and others may read
    summary = json.loads((out / "summary.json").read_text())
    assert summary["scene"] == "hanging" and summary["omega_m"] == 0.0
    (out / "summary.json").write_text("stale")
    assert run_cli(args, capsys)[0] == 0  # a previous results folder is replaced
    assert json.loads((out / "summary.json").read_text())["scene"] == "hanging"
    assert [p.name for p in tmp_path.iterdir()] == ["res"]


def test_hessian_exact_runs_the_interpreted_model(capsys):
    parser = cli.build_parser()
    args = parser.parse_args(["optimize", HANGING, "--out", "o", "--hessian", "exact"])
    settings = cli._ipopt_settings(args)
    assert settings.hessian == "exact" and settings.compiled is False
    assert "--hessian exact runs the interpreted model" in capsys.readouterr().err
    args = parser.parse_args(["optimize", HANGING, "--out", "o"])
    assert cli._ipopt_settings(args).compiled is True


@pytest.mark.parametrize(
    ("flags", "quiet", "verbose"),
    [([], False, False), (["--verbose"], False, True), (["--quiet"], True, False)],
)
@pytest.mark.parametrize("command", ["optimize", "compare"])
def test_quiet_and_verbose_reach_the_optimiser(
    tmp_path, monkeypatch, capsys, command, flags, quiet, verbose
):
    calls = []

    def record(scene, method, settings, **kwargs):
        calls.append(kwargs)
        raise ValueError("stopped by the test")

    monkeypatch.setattr(optimization, "optimize", record)
    code, _, err = run_cli([command, HANGING, "--out", tmp_path / "o", *flags], capsys)
    assert code == 2 and "stopped by the test" in err
    assert calls[0]["quiet"] is quiet and calls[0]["verbose"] is verbose


@pytest.mark.parametrize(
    ("error", "code", "line"),
    [
        (KeyboardInterrupt(), 130, "cable-ocp simulate: interrupted"),
        (OSError(28, "No space left on device"),
         1, "cable-ocp simulate: error: [Errno 28] No space left on device"),
        (OverflowError("math range\nerror"), 2, "cable-ocp simulate: error: math range error"),
    ],
)  # fmt: skip
def test_interrupt_and_system_errors_have_no_traceback(
    tmp_path, monkeypatch, capsys, error, code, line
):
    def fail(*args, **kwargs):
        raise error

    monkeypatch.setattr(cli, "load_scene", fail)
    result, out, err = run_cli(["simulate", HANGING, "--out", tmp_path / "o"], capsys)
    assert result == code
    assert err == line + "\n" and out == ""


def test_help_exits_0(capsys):
    assert cli.main(["--help"]) == 0
    assert "simulate" in capsys.readouterr().out


def _console_script() -> list[str]:
    script = shutil.which("cable-ocp")
    return [script] if script else [sys.executable, "-m", "cable_ocp.cli"]


def test_console_script_exit_codes_end_to_end(tmp_path):
    (tmp_path / "notes.txt").write_text("keep me")
    runs = {
        "missing": ["simulate", "missing.toml", "--out", "res"],
        "cwd": ["simulate", HANGING, "--out", "."],
    }
    for name, args in runs.items():
        done = subprocess.run(_console_script() + args, cwd=tmp_path, capture_output=True,
                              text=True, timeout=120)  # fmt: skip
        assert done.returncode == 2, name
        assert done.stderr.count("\n") == 1 and done.stderr.startswith("cable-ocp simulate: error")
        assert "Traceback" not in done.stderr + done.stdout
    assert [p.name for p in tmp_path.iterdir()] == ["notes.txt"]
    assert (tmp_path / "notes.txt").read_text() == "keep me"
